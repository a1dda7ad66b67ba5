#!/usr/bin/env bash
# README's first command, the main job on a fresh Debian 12 machine: install the dependencies, build,
# start glimpse-server on an embedded SQLite file, train a model on the procedural shape zoo, stream a
# partial top-down scan of an object the model never saw and print the evolving decisions, stop.
#   deploy/demo.sh [--data DIR]     DIR/<category>/<meshes or clouds> instead of the zoo
# Environment: GLIMPSE_BUILD_DIR (default build), GLIMPSE_DEMO_PORT (default 50151).
set -euo pipefail
cd "$(dirname "$0")/.."

data=""
if [[ "${1:-}" == "--data" ]]; then
  data="${2:?--data needs a folder}"
  [[ -d "$data" ]] || { echo "demo: no such folder: $data" >&2; exit 2; }
elif [[ $# -gt 0 ]]; then
  echo "usage: deploy/demo.sh [--data DIR]" >&2
  exit 2
fi

bash deploy/install-deps.sh
build_dir="${GLIMPSE_BUILD_DIR:-build}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build_dir" -j "$(nproc)" --target glimpse-server glimpse

server_bin="$build_dir/server/glimpse-server"
glimpse="$build_dir/client/glimpse"
port="${GLIMPSE_DEMO_PORT:-50151}"
export GLIMPSE_SERVER="127.0.0.1:$port"
state="$(mktemp -d)"
"$server_bin" --address="$GLIMPSE_SERVER" --db="$state/glimpse.db" --metrics-port=0 >"$state/server.log" 2>&1 &
server_pid=$!
stop_server() {
  kill -TERM "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null || true
  rm -rf "$state"
}
trap stop_server EXIT

for _ in $(seq 100); do
  "$glimpse" health >/dev/null 2>&1 && break
  kill -0 "$server_pid" 2>/dev/null || { echo "demo: the server did not start:" >&2; cat "$state/server.log" >&2; exit 1; }
  sleep 0.1
done
echo "== glimpse-server is $("$glimpse" health) on $GLIMPSE_SERVER (model store: $state/glimpse.db)"

echo "== training on $( [[ -n "$data" ]] && echo "$data" || echo "the procedural shape zoo (6 objects per category, 6 views each)")"
if [[ -n "$data" ]]; then
  "$glimpse" train "$data" --name demo
else
  "$glimpse" train --zoo --per-category 6 --seed 1 --name demo
fi

# A zoo human the model has not seen (another seed), revealed top to bottom as a scanner would see it.
echo "== streaming an unseen human, top to bottom, 25 chunks"
"$glimpse" stream --zoo human --seed 1234 --model demo --chunks 25 --rate 10
echo "== stopping the server"
