# Sourced by the client end-to-end tests: start the real glimpse-server on a free loopback port with
# a temporary model store, wait until it reports SERVING, and stop it on exit whatever happens.
#   start_server SERVER_BINARY GLIMPSE_BINARY   sets GLIMPSE_TEST_TMP, SERVER_PID, GLIMPSE_SERVER
# The caller's `trap stop_server EXIT` (set here) kills the server and removes the temp folder.

GLIMPSE_TEST_TMP=$(mktemp -d "${TMPDIR:-/tmp}/glimpse-client-e2e.XXXXXX")
SERVER_PID=""

stop_server() {
  local rc=$?
  if [[ -n "$SERVER_PID" ]] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$SERVER_PID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$SERVER_PID" 2>/dev/null
    wait "$SERVER_PID" 2>/dev/null
  fi
  if ((rc != 0)) && [[ -f "$GLIMPSE_TEST_TMP/server.log" ]]; then
    echo "---- server log (last 30 lines) ----" >&2
    tail -n 30 "$GLIMPSE_TEST_TMP/server.log" >&2
  fi
  rm -rf "$GLIMPSE_TEST_TMP"
  exit $rc
}
trap stop_server EXIT
trap 'exit 130' INT TERM

# A port nobody listens on right now (the kernel's choice for an ephemeral bind).
free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

PDEATHSIG=""
if command -v setpriv >/dev/null && setpriv --help 2>&1 | grep -q pdeathsig; then PDEATHSIG="setpriv --pdeathsig KILL --"; fi

start_server() {
  local server_bin=$1 glimpse_bin=$2
  for attempt in 1 2 3; do
    local port
    port=$(free_port)
    # setpriv --pdeathsig: the server dies with this script even if it is SIGKILLed (ctest timeout).
    $PDEATHSIG "$server_bin" --address "127.0.0.1:$port" --db "$GLIMPSE_TEST_TMP/models.db" --metrics-port 0 \
      >"$GLIMPSE_TEST_TMP/server.log" 2>&1 &
    SERVER_PID=$!
    export GLIMPSE_SERVER="127.0.0.1:$port"
    for _ in $(seq 100); do  # up to ~20 s
      if ! kill -0 "$SERVER_PID" 2>/dev/null; then break; fi
      if "$glimpse_bin" health --timeout 1 >/dev/null 2>&1; then return 0; fi
      sleep 0.2
    done
    echo "server did not become SERVING on port $port (attempt $attempt)" >&2
    kill -KILL "$SERVER_PID" 2>/dev/null
    wait "$SERVER_PID" 2>/dev/null
    SERVER_PID=""
  done
  return 1
}
