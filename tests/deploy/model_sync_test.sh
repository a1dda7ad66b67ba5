#!/usr/bin/env bash
# How a new model version reaches running replicas (deploy/README.md, deploy/k8s): a trainer server
# writes its own store; deploy/model-sync.sh publishes a snapshot of it; a replica server with its
# own store pulls the snapshot into its live file and serves the new versions with no restart.
#   model_sync_test.sh GLIMPSE_BINARY SERVER_BINARY MODEL_SYNC_SCRIPT
# Real glimpse-server processes on loopback ports, the real client, sqlite3. About 30 s.
set -euo pipefail
GLIMPSE=$1
SERVER=$2
SYNC=$3
TMP=$(mktemp -d "${TMPDIR:-/tmp}/glimpse-model-sync.XXXXXX")
PIDS=()

cleanup() {
  local rc=$?
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${PIDS[@]}"; do wait "$pid" 2>/dev/null || true; done
  if ((rc != 0)); then
    for log in "$TMP"/*.log; do [[ -f $log ]] && { echo "---- $log" >&2; tail -n 20 "$log" >&2; }; done
  fi
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }
free_port() { /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

# start NAME STORE: a server on a free port; sets PORT_<NAME>.
start() {
  local name=$1 store=$2 port
  port=$(free_port)
  "$SERVER" --address "127.0.0.1:$port" --db "$store" --metrics-port 0 >"$TMP/$name.log" 2>&1 &
  PIDS+=($!)
  for _ in $(seq 100); do
    if timeout 5 "$GLIMPSE" --server "127.0.0.1:$port" health --timeout 1 >/dev/null 2>&1; then
      printf -v "PORT_$name" '%s' "$port"
      return 0
    fi
    sleep 0.2
  done
  fail "server $name did not become SERVING"
}
at() { local port="PORT_$1"; shift; timeout 120 "$GLIMPSE" --server "127.0.0.1:${!port}" "$@"; }
versions() { at "$1" models list "$2" --json | grep -c '"name":"'"$2"'"' || true; }

start trainer "$TMP/trainer/glimpse.db"
start replica "$TMP/replica/glimpse.db"
PUBLISHED="$TMP/published/glimpse.db"

# Nothing published yet: pulling is a no-op, not an error.
bash -c "\"$SYNC\" pull \"$PUBLISHED\" \"$TMP/replica/glimpse.db\"" 2>"$TMP/pull0.err" || fail "pull of nothing failed"
grep -q "nothing published" "$TMP/pull0.err" || fail "pull of nothing said: $(cat "$TMP/pull0.err")"

at trainer train --zoo --per-category 2 --views 2 --methods bok,esf --name shapes --quiet >/dev/null || fail "train v1"
"$SYNC" publish "$TMP/trainer/glimpse.db" "$PUBLISHED" 2>/dev/null || fail "publish v1"
[[ $(sqlite3 "file:$PUBLISHED?mode=ro" "PRAGMA journal_mode;") == delete ]] || fail "the snapshot is not in rollback-journal mode"
[[ ! -e "$PUBLISHED-wal" ]] || fail "the snapshot has a -wal file beside it"

# The published folder read-only, as the replicas mount it (root ignores permissions; still, no writes).
chmod a-w "$TMP/published"
[[ $(versions replica shapes) -eq 0 ]] || fail "the replica has models before any pull"
"$SYNC" pull "$PUBLISHED" "$TMP/replica/glimpse.db" 2>/dev/null || fail "pull v1"
[[ $(versions replica shapes) -eq 1 ]] || fail "the running replica does not list shapes:1 after the pull"
at replica stream --zoo chair --model shapes --rate 0 --chunks 3 >/dev/null || fail "the replica cannot classify with shapes"
[[ ! -e "$TMP/published/glimpse.db-shm" && ! -e "$TMP/published/glimpse.db-journal" ]] || fail "pull wrote beside the snapshot"
chmod u+w "$TMP/published"

# The sidecar loop: pulls every second; a second published version reaches the replica unattended.
"$SYNC" pull "$PUBLISHED" "$TMP/replica/glimpse.db" 1 2>"$TMP/sync.log" &
PIDS+=($!)
at trainer train --zoo --per-category 2 --views 2 --methods bok,esf --seed 5 --name shapes --quiet >/dev/null || fail "train v2"
"$SYNC" publish "$TMP/trainer/glimpse.db" "$PUBLISHED" 2>/dev/null || fail "publish v2"
for _ in $(seq 50); do
  [[ $(versions replica shapes) -eq 2 ]] && break
  sleep 0.2
done
[[ $(versions replica shapes) -eq 2 ]] || fail "the replica does not list shapes:2 within 10 s of publishing"
out=$(at replica stream --zoo human --model shapes --rate 0 --chunks 3 --json) || fail "classify with shapes:2"
grep -q '"version":2' <<<"$out" || fail "the replica's default is not the new version 2: $(tail -n 1 <<<"$out")"
kill -0 "${PIDS[1]}" 2>/dev/null || fail "the replica server exited"

# A broken snapshot is refused and leaves the replica serving what it had.
echo "not a database" >"$TMP/bad.db"
if "$SYNC" pull "$TMP/bad.db" "$TMP/replica/glimpse.db" 2>/dev/null; then fail "pull of a non-database succeeded"; fi
[[ $(versions replica shapes) -eq 2 ]] || fail "a failed pull changed the replica's models"
echo "model_sync_test: 1 passed, 0 failed"
