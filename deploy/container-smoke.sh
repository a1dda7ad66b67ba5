#!/usr/bin/env bash
# Builds the Glimpse image with podman and proves it works: serve, train, classify, health (the
# client's and the image's HEALTHCHECK), metrics, a new model version reaching a running server
# without restart (a second server process on the same file, and a replica pulling a published
# snapshot), and the models surviving a container restart on the volume.
#
#   deploy/container-smoke.sh          (as root, or with sudo for the package installs)
#
# Idempotent: installs podman/buildah/runc/debootstrap when missing, creates the debian:bookworm base
# image with debootstrap when it is missing (no image registry is reachable here), removes what an
# earlier run left behind, and cleans up after itself (the image stays, so the next run is warm).
# Environment:
#   GLIMPSE_IMAGE          image tag to build and run [localhost/glimpse:smoke]
#   GLIMPSE_SMOKE_WORK     scratch folder (debootstrap rootfs, test files) [/var/tmp/glimpse-smoke]
#   GLIMPSE_CLIENT         a host-built `glimpse` to use instead of the image's (over the published port)
#   GLIMPSE_SMOKE_KEEP=1   leave the containers and volume running for a look afterwards
#   GLIMPSE_SMOKE_NO_LINT=1  skip dockerfilelint (it comes from npm)
#   GLIMPSE_SMOKE_GIT_REV  build a `git archive` of this revision (e.g. HEAD) instead of the work tree
# Exit status: 0 when every check passed, 1 at the first failure (its phase and the server's log
# are printed).
set -euo pipefail
cd "$(dirname "$0")/.."

IMAGE=${GLIMPSE_IMAGE:-localhost/glimpse:smoke}
BASE=docker.io/library/debian:bookworm
WORK=${GLIMPSE_SMOKE_WORK:-/var/tmp/glimpse-smoke}
NAME=glimpse-smoke
REPLICA=glimpse-smoke-replica
VOLUME=glimpse-smoke-db
# runc, and ulimits podman can set: crun fails on this kind of machine, and podman's defaults for
# nofile/nproc are above what the sandbox allows.
RUN_FLAGS=(--runtime runc --ulimit nofile=1024:1024 --ulimit nproc=1024:1024)

# ---- reporting ---------------------------------------------------------------------------------
PHASE="" PHASE_START=0 RUN_START=$(date +%s.%N)
SUMMARY=()
now() { date +%s.%N; }
seconds_since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
phase() {
  end_phase
  PHASE=$1 PHASE_START=$(now)
  echo "==> $PHASE"
}
end_phase() {
  if [[ -n $PHASE ]]; then
    local took
    took=$(seconds_since "$PHASE_START")
    SUMMARY+=("$(printf '  %-52s %7s s' "$PHASE" "$took")")
    echo "    ok: $PHASE ($took s)"
  fi
  PHASE=""
}
fail() {
  echo "FAIL [$PHASE]: $*" >&2
  exit 1
}
on_exit() {
  local rc=$?
  if ((rc != 0)); then
    echo "---- FAIL in phase '${PHASE:-setup}' after $(seconds_since "$RUN_START") s (exit $rc)" >&2
    if podman container exists "$NAME" 2>/dev/null; then
      echo "---- last lines of the server's log ($NAME):" >&2
      podman logs --tail 30 "$NAME" >&2 2>&1 || true
    fi
  fi
  if [[ ${GLIMPSE_SMOKE_KEEP:-0} != 1 ]] && command -v podman >/dev/null; then cleanup; fi
  if ((rc == 0)); then echo "PASS: container smoke test"; else echo "FAIL: container smoke test" >&2; fi
}
trap on_exit EXIT
cleanup() {
  podman rm -f -t 5 "$NAME" "$REPLICA" >/dev/null 2>&1 || true
  podman volume rm -f "$VOLUME" >/dev/null 2>&1 || true
}

# ---- helpers -------------------------------------------------------------------------------------
SUDO=""
[[ $(id -u) -eq 0 ]] || SUDO="sudo"

# The Debian mirror this machine's apt uses (deb822 "URIs:" or one-line "deb URL bookworm ...").
apt_mirror() {
  local files=(/etc/apt/sources.list /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list) f uri
  for f in "${files[@]}"; do
    [[ -f $f ]] || continue
    uri=$(awk '
      /^[[:space:]]*URIs:/ { uri = $2 }
      /^[[:space:]]*Suites:/ { for (i = 2; i <= NF; i++) if ($i == "bookworm" && uri != "") { print uri; exit } }
      /^[[:space:]]*deb[[:space:]]/ { for (i = 3; i <= NF; i++) if ($i == "bookworm") { print ($2 ~ /^\[/ ? $3 : $2); exit } }
    ' "$f")
    if [[ -n $uri ]]; then echo "$uri"; return; fi
  done
  echo "http://deb.debian.org/debian"
}

free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# The client: a host binary over the published port, or the image's client in a container on the
# host's network (so the published port is what it reaches, not the server's own).
client() {
  if [[ -n ${GLIMPSE_CLIENT:-} ]]; then
    "$GLIMPSE_CLIENT" --server "127.0.0.1:$GRPC_PORT" "$@"
  else
    podman run --rm "${RUN_FLAGS[@]}" --no-healthcheck --network host -v "$WORK/data:/data:ro" --entrypoint glimpse "$IMAGE" \
      --server "127.0.0.1:$GRPC_PORT" "$@"
  fi
}

# wait_healthy SECONDS CMD...: until CMD prints SERVING and exits 0.
wait_healthy() {
  local limit=$1 start out=""
  shift
  start=$(date +%s)
  until out=$("$@" 2>"$WORK/health.err") && [[ $out == SERVING ]]; do
    (($(date +%s) - start < limit)) || fail "not SERVING after ${limit} s: $out $(tail -n 3 "$WORK/health.err")"
    sleep 0.5
  done
}

http_get() {  # http_get PORT PATH: the body of a plain HTTP/1.0 GET to 127.0.0.1
  exec 3<>"/dev/tcp/127.0.0.1/$1" || return 1
  printf 'GET %s HTTP/1.0\r\nHost: localhost\r\n\r\n' "$2" >&3
  cat <&3
  exec 3<&-
}

health_status() {  # the container's HEALTHCHECK state (podman 4.3 calls it Healthcheck)
  podman inspect --format '{{.State.Healthcheck.Status}}' "$1" 2>/dev/null ||
    podman inspect --format '{{.State.Health.Status}}' "$1"
}

# ---- phases --------------------------------------------------------------------------------------
mkdir -p "$WORK/data"

phase "tools (podman buildah runc debootstrap)"
missing=()
for pkg in podman buildah runc debootstrap; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "    installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
for tool in podman runc python3; do command -v "$tool" >/dev/null || fail "$tool is not installed"; done
podman --version

phase "base image $BASE"
if podman image exists "$BASE"; then
  echo "    present"
else
  mirror=$(apt_mirror)
  echo "    debootstrap --variant=minbase bookworm from $mirror"
  rootfs="$WORK/rootfs"
  $SUDO rm -rf "$rootfs"  # a partial one from an interrupted run
  mkdir -p "$WORK"
  $SUDO debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$WORK/debootstrap.log" 2>&1 ||
    fail "debootstrap failed; see $WORK/debootstrap.log"
  # As Docker's official image: no downloaded .debs, no package lists (every build runs apt-get update).
  $SUDO find "$rootfs/var/cache/apt/archives" "$rootfs/var/lib/apt/lists" -type f -delete
  $SUDO tar -C "$rootfs" -c . | podman import - "$BASE" >/dev/null 2>"$WORK/import.log" ||
    fail "podman import failed: $(tail -n 3 "$WORK/import.log")"
  $SUDO rm -rf "$rootfs"
  podman image exists "$BASE" || fail "import of $BASE failed"
fi

CONTEXT=.
if [[ -n ${GLIMPSE_SMOKE_GIT_REV:-} ]]; then
  phase "context: git archive $GLIMPSE_SMOKE_GIT_REV"
  CONTEXT="$WORK/context"
  rm -rf "$CONTEXT"
  mkdir -p "$CONTEXT"
  git archive "$GLIMPSE_SMOKE_GIT_REV" | tar -x -C "$CONTEXT" || fail "git archive $GLIMPSE_SMOKE_GIT_REV failed"
fi

if [[ ${GLIMPSE_SMOKE_NO_LINT:-0} != 1 ]]; then
  phase "lint (dockerfilelint)"
  if command -v dockerfilelint >/dev/null; then
    dockerfilelint "$CONTEXT/Dockerfile" || fail "dockerfilelint reports issues"
  else
    npx --yes dockerfilelint@1.8.0 "$CONTEXT/Dockerfile" || fail "dockerfilelint (npx) reports issues or could not run"
  fi
fi

phase "build $IMAGE"
# --format docker: OCI image configs have no HEALTHCHECK.
podman build --format docker "${RUN_FLAGS[@]}" -t "$IMAGE" -f "$CONTEXT/Dockerfile" "$CONTEXT" >"$WORK/build.log" 2>&1 ||
  { tail -40 "$WORK/build.log" >&2; fail "podman build failed; full log in $WORK/build.log"; }
echo "    $(podman image inspect --format '{{.Id}} {{.Size}} bytes' "$IMAGE")"

phase "image checks (user, ports, healthcheck, libraries)"
user=$(podman image inspect --format '{{.Config.User}}' "$IMAGE")
[[ -n $user && $user != root && $user != 0 ]] || fail "the image runs as '${user:-root}', not a non-root user"
ports=$(podman image inspect --format '{{range $p, $_ := .Config.ExposedPorts}}{{$p}} {{end}}' "$IMAGE")
[[ $ports == *50051/tcp* && $ports == *9464/tcp* ]] || fail "exposed ports are '$ports', want 50051/tcp and 9464/tcp"
hc=$(podman image inspect --format '{{.Config.Healthcheck}}' "$IMAGE")
[[ $hc == *glimpse*health* ]] || fail "no HEALTHCHECK with glimpse health: '$hc'"
missing_libs=$(podman run --rm "${RUN_FLAGS[@]}" --no-healthcheck --entrypoint sh "$IMAGE" -c \
  'ldd /usr/local/bin/glimpse-server /usr/local/bin/glimpse | grep "not found" || true')
[[ -z $missing_libs ]] || fail "libraries missing in the runtime image: $missing_libs"
podman run --rm "${RUN_FLAGS[@]}" --no-healthcheck --entrypoint glimpse-server "$IMAGE" --help >/dev/null || fail "glimpse-server --help"
podman run --rm "${RUN_FLAGS[@]}" --no-healthcheck --entrypoint glimpse "$IMAGE" --help >/dev/null || fail "glimpse --help"
echo "    user $user; exposes $ports; ldd: every library found"

phase "run the server"
cleanup
GRPC_PORT=$(free_port)
METRICS_PORT=$(free_port)
podman volume create "$VOLUME" >/dev/null
# Without systemd (as here) podman cannot schedule the periodic HEALTHCHECK and says so on stderr;
# the check itself still runs on `podman healthcheck run` below.
podman run -d --name "$NAME" "${RUN_FLAGS[@]}" -p "127.0.0.1:$GRPC_PORT:50051" -p "127.0.0.1:$METRICS_PORT:9464" \
  -v "$VOLUME:/var/lib/glimpse" "$IMAGE" >/dev/null 2>"$WORK/run.err" || fail "podman run: $(cat "$WORK/run.err")"
wait_healthy 60 client health
echo "    SERVING on 127.0.0.1:$GRPC_PORT, metrics on 127.0.0.1:$METRICS_PORT"

phase "train smoke (zoo, 3 per category)"
out=$(client train --zoo --name smoke --per-category 3 --quiet --json) || fail "train failed: $out"
[[ $out == *'"name":"smoke"'* ]] || fail "train printed no model named smoke: $out"
[[ $out =~ \"version\":1[,}] ]] || fail "the first model is not version 1: $out"

phase "classify (stream and file)"
out=$(client stream --zoo human --model smoke --rate 0 --json) || fail "stream failed: $out"
decisions=$(grep -c '"winner"' <<<"$out" || true)
((decisions > 0)) || fail "stream gave no decisions: $out"
echo "    stream: $decisions decisions, last: $(tail -n 1 <<<"$out" | cut -c1-160)"
# A 0.4 x 0.4 x 0.8 m box as an OFF mesh; the client samples its surface.
cat >"$WORK/data/box.off" <<'MESH'
OFF
8 12 0
0 0 0
0.4 0 0
0.4 0.4 0
0 0.4 0
0 0 0.8
0.4 0 0.8
0.4 0.4 0.8
0 0.4 0.8
3 0 2 1
3 0 3 2
3 4 5 6
3 4 6 7
3 0 1 5
3 0 5 4
3 1 2 6
3 1 6 5
3 2 3 7
3 2 7 6
3 3 0 4
3 3 4 7
MESH
box=/data/box.off
[[ -n ${GLIMPSE_CLIENT:-} ]] && box="$WORK/data/box.off"
out=$(client classify --model smoke --json "$box") || fail "classify failed: $out"
[[ $out == *'"winner"'* ]] || fail "classify gave no winner: $out"
echo "    classify box.off: $(cut -c1-160 <<<"$out")"

phase "health (client and HEALTHCHECK)"
[[ $(client health) == SERVING ]] || fail "glimpse health is not SERVING"
podman healthcheck run "$NAME" >/dev/null 2>&1 || fail "the image's HEALTHCHECK fails"
status=$(health_status "$NAME")
[[ $status == healthy ]] || fail "container health is '$status', not healthy"
echo "    glimpse health: SERVING; HEALTHCHECK: $status"

phase "metrics port"
metrics=$(http_get "$METRICS_PORT" /metrics) || fail "no answer on the metrics port $METRICS_PORT"
[[ $metrics == *"200 OK"* ]] || fail "metrics did not answer 200: $(head -1 <<<"$metrics")"
grep -q '^glimpse_rpc_requests_total{.*Classify' <<<"$metrics" || fail "no Classify count in /metrics"
grep -q '^glimpse_models_loaded' <<<"$metrics" || fail "no glimpse_models_loaded in /metrics"
echo "    $(grep -c '^glimpse_' <<<"$metrics") glimpse_* samples"

phase "hot reload: second server on the same file"
# Another server process on the same store (as a trainer beside the replicas would be) writes
# version 2; the first server serves it at once, with no restart.
podman exec "$NAME" sh -c 'glimpse-server --address 127.0.0.1:50052 --metrics-port 0 >/tmp/second.log 2>&1 &
  echo $! >/tmp/second.pid'
wait_healthy 30 podman exec "$NAME" glimpse --server 127.0.0.1:50052 health
podman exec "$NAME" glimpse --server 127.0.0.1:50052 train --zoo --name smoke --per-category 2 --seed 2 --quiet >/dev/null ||
  fail "training version 2 through the second server failed"
podman exec "$NAME" sh -c 'kill -TERM "$(cat /tmp/second.pid)"'
out=$(client models list smoke --json) || fail "models list failed: $out"
[[ $(grep -c '"name":"smoke"' <<<"$out") -eq 2 ]] ||
  fail "the first server does not list both versions of smoke: $out"
out=$(client classify --model smoke:2 --json "$box") || fail "classify with smoke:2 on the first server failed: $out"
echo "    the first server lists smoke:1 and smoke:2 and classifies with smoke:2"

phase "hot reload: replica pulls a published snapshot"
# The Kubernetes layout (deploy/k8s): the trainer publishes a snapshot, a replica with its own store
# mounts it read-only and pulls it into its live store.
podman exec "$NAME" glimpse-model-sync publish /var/lib/glimpse/glimpse.db /var/lib/glimpse/published/glimpse.db
# Locked like the k8s replicas: a token nobody is given guards Train/DeleteModel/SetDefaultModel.
head -c 24 /dev/urandom | base64 >"$WORK/data/lock-token"
chmod 0644 "$WORK/data/lock-token"
podman run -d --name "$REPLICA" "${RUN_FLAGS[@]}" --mount "type=volume,src=$VOLUME,dst=/models,ro=true" \
  -v "$WORK/data/lock-token:/etc/glimpse/lock/token:ro" -e GLIMPSE_AUTH_TOKEN_FILE=/etc/glimpse/lock/token \
  "$IMAGE" >/dev/null 2>"$WORK/run.err" || fail "podman run (replica): $(cat "$WORK/run.err")"
wait_healthy 30 podman exec "$REPLICA" glimpse health
before=$(podman exec "$REPLICA" glimpse models list --json)
[[ -z $before ]] || fail "the new replica is not empty: $before"
podman exec "$REPLICA" glimpse-model-sync pull /models/published/glimpse.db /var/lib/glimpse/glimpse.db
out=$(podman exec "$REPLICA" glimpse models list smoke --json)
[[ $(grep -c '"name":"smoke"' <<<"$out") -eq 2 ]] || fail "the replica does not serve both pulled versions: $out"
podman exec "$REPLICA" glimpse stream --zoo chair --model smoke --rate 0 >/dev/null || fail "the replica cannot classify"
if err=$(podman exec "$REPLICA" glimpse models delete smoke:1 2>&1); then fail "the locked replica deleted a model"; fi
[[ $err == *UNAUTHENTICATED* ]] || fail "the locked replica refused a delete without saying UNAUTHENTICATED: $err"
podman rm -f -t 5 "$REPLICA" >/dev/null 2>&1
echo "    the replica serves smoke:1 and smoke:2 without a restart, and refuses model changes"

phase "restart: models survive on the volume"
podman restart -t 15 "$NAME" >/dev/null 2>"$WORK/run.err" || fail "podman restart: $(cat "$WORK/run.err")"
wait_healthy 60 client health
out=$(client models list smoke --json) || fail "models list after restart failed: $out"
[[ $(grep -c '"name":"smoke"' <<<"$out") -eq 2 ]] || fail "after the restart smoke has not 2 versions: $out"
client classify --model smoke --json "$box" >/dev/null || fail "classify after restart failed"
podman logs "$NAME" 2>&1 | grep -q "SIGTERM" || fail "the server log shows no SIGTERM drain on restart"

phase "cleanup"
if [[ ${GLIMPSE_SMOKE_KEEP:-0} == 1 ]]; then echo "    kept $NAME and $VOLUME"; else cleanup; fi
end_phase

echo "---- phases"
printf '%s\n' "${SUMMARY[@]}"
printf '  %-52s %7s s\n' "total" "$(seconds_since "$RUN_START")"
