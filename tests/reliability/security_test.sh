#!/usr/bin/env bash
# Security end to end: the real glimpse-server with TLS, mutual TLS and a bearer
# token, driven by the real glimpse CLI. A throwaway CA, server and client certificates are made with
# openssl in a temporary folder at test time (no key is ever committed).
#   security_test.sh GLIMPSE_BINARY SERVER_BINARY
# Checks: TLS works with the client (--tls --ca); a plaintext client fails; mutual TLS refuses a
# client without a certificate (or with one from another CA) and accepts ours; the token is required
# exactly on Train, DeleteModel and SetDefaultModel; bad TLS files are clear startup errors; the
# server log never contains the token. About 40 s.
set -uo pipefail
GLIMPSE=$(realpath "$1")
SERVER=$(realpath "$2")
TMP=$(mktemp -d "${TMPDIR:-/tmp}/glimpse-security.XXXXXX")
SERVER_PID=""
FAILURES=0
TOKEN="tok-$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')"

stop_server() {
  if [[ -n "$SERVER_PID" ]] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$SERVER_PID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$SERVER_PID" 2>/dev/null
  fi
  [[ -n "$SERVER_PID" ]] && wait "$SERVER_PID" 2>/dev/null
  SERVER_PID=""
}
cleanup() {
  local rc=$?
  stop_server
  if ((rc != 0)); then for f in "$TMP"/server-*.log; do echo "---- $f" >&2; tail -n 15 "$f" >&2; done; fi
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

fail() { echo "FAIL: $*" >&2; echo "  stderr: $(head -c 600 "$TMP/err")" >&2; FAILURES=$((FAILURES + 1)); }
free_port() { /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
PDEATHSIG=""
if command -v setpriv >/dev/null && setpriv --help 2>&1 | grep -q pdeathsig; then PDEATHSIG="setpriv --pdeathsig KILL --"; fi

# ---- certificates: CA -> server (SAN 127.0.0.1, localhost) and client; a second, foreign CA ----
cd "$TMP" || exit 1
cert() {  # cert NAME SUBJECT CA [SAN]
  local name=$1 subject=$2 ca=$3 san=${4:-}
  openssl req -newkey rsa:2048 -nodes -keyout "$name.key" -subj "$subject" -out "$name.csr" 2>/dev/null || return 1
  if [[ -n "$san" ]]; then printf 'subjectAltName=%s\n' "$san" >"$name.ext"; else : >"$name.ext"; fi
  openssl x509 -req -in "$name.csr" -CA "$ca.pem" -CAkey "$ca.key" -CAcreateserial -days 2 -sha256 \
    -extfile "$name.ext" -out "$name.pem" 2>/dev/null
}
for ca in ca other-ca; do
  openssl req -x509 -newkey rsa:2048 -nodes -keyout "$ca.key" -subj "/CN=glimpse test $ca" -days 2 \
    -out "$ca.pem" 2>/dev/null || { echo "openssl cannot make a CA" >&2; exit 1; }
done
cert server "/CN=localhost" ca "DNS:localhost,IP:127.0.0.1" || exit 1
cert client "/CN=glimpse test client" ca || exit 1
cert stranger "/CN=stranger" other-ca || exit 1
chmod 600 ./*.key

# start_server NAME ARGS...: on a free port; waits until the port accepts connections.
start_server() {
  local name=$1
  shift
  PORT=$(free_port)
  $PDEATHSIG "$SERVER" --address "127.0.0.1:$PORT" --db "$TMP/$name.db" --metrics-port 0 "$@" \
    >"$TMP/server-$name.log" 2>&1 &
  SERVER_PID=$!
  for _ in $(seq 100); do
    kill -0 "$SERVER_PID" 2>/dev/null || return 1
    (exec 3<>"/dev/tcp/127.0.0.1/$PORT") 2>/dev/null && return 0
    sleep 0.1
  done
  return 1
}
# run EXPECTED_RC glimpse-args...
run() {
  local expected=$1
  shift
  timeout 120 "$GLIMPSE" --server "127.0.0.1:$PORT" "$@" >"$TMP/out" 2>"$TMP/err"
  local rc=$?
  ((rc == expected)) || { fail "glimpse $* exited $rc, expected $expected"; return 1; }
}
err_has() { grep -qE -- "$1" "$TMP/err" || fail "stderr lacks /$1/ ($2)"; }

TLS=(--tls --ca "$TMP/ca.pem")
MTLS=(--tls --ca "$TMP/ca.pem" --cert "$TMP/client.pem" --key "$TMP/client.key")

# ---- TLS: the client with our CA works, plaintext and an untrusting client fail ----
start_server tls --tls-cert "$TMP/server.pem" --tls-key "$TMP/server.key" || { echo "TLS server did not start" >&2; exit 1; }
run 0 "${TLS[@]}" health
run 0 "${TLS[@]}" train --zoo --per-category 1 --views 2 --methods esf,vfh --name zoo -q
run 0 "${TLS[@]}" models list
run 1 health --timeout 3 && err_has "UNAVAILABLE" "plaintext client against a TLS port"
run 1 --tls --ca "$TMP/other-ca.pem" health --timeout 3 && err_has "UNAVAILABLE" "a CA that did not sign the server"
grep -q "serving glimpse.v1.Glimpse.*TLS" "$TMP/server-tls.log" || fail "the start line does not say TLS"
stop_server

# ---- mutual TLS: a client certificate from our CA is required ----
start_server mtls --tls-cert "$TMP/server.pem" --tls-key "$TMP/server.key" --tls-client-ca "$TMP/ca.pem" ||
  { echo "mTLS server did not start" >&2; exit 1; }
run 0 "${MTLS[@]}" health
run 0 "${MTLS[@]}" train --zoo --per-category 1 --views 2 --methods esf,vfh --name zoo -q
run 1 "${TLS[@]}" health --timeout 3 && err_has "UNAVAILABLE" "mTLS without a client certificate"
run 1 --tls --ca "$TMP/ca.pem" --cert "$TMP/stranger.pem" --key "$TMP/stranger.key" health --timeout 3 &&
  err_has "UNAVAILABLE" "mTLS with a certificate of another CA"
run 1 health --timeout 3
grep -q "mutual TLS" "$TMP/server-mtls.log" || fail "the start line does not say mutual TLS"
stop_server

# ---- bad TLS files: clear startup errors naming the file, never its contents ----
bad_start() {  # bad_start PATTERN ARGS...
  local pattern=$1
  shift
  timeout 20 "$SERVER" --address "127.0.0.1:$(free_port)" --db "$TMP/bad.db" --metrics-port 0 "$@" >"$TMP/err" 2>&1
  local rc=$?
  ((rc != 0)) || fail "the server started with $*"
  err_has "$pattern" "startup with $*"
  if grep -q "PRIVATE KEY" "$TMP/err"; then fail "a startup error printed key material"; fi
}
bad_start "client.key does not belong to the certificate" --tls-cert "$TMP/server.pem" --tls-key "$TMP/client.key"
bad_start "not a PEM certificate" --tls-cert "$TMP/server.key" --tls-key "$TMP/server.key"
bad_start "nope.pem: cannot be read" --tls-cert "$TMP/nope.pem" --tls-key "$TMP/server.key"
bad_start "--tls-cert and --tls-key go together" --tls-cert "$TMP/server.pem"
bad_start "needs --tls-cert" --tls-client-ca "$TMP/ca.pem"
bad_start "auth token file .*empty" --auth-token-file /dev/null

# ---- the bearer token: exactly Train, DeleteModel and SetDefaultModel need it ----
printf '%s\n' "$TOKEN" >"$TMP/token"
chmod 600 "$TMP/token"
start_server token --tls-cert "$TMP/server.pem" --tls-key "$TMP/server.key" --auth-token-file "$TMP/token" ||
  { echo "token server did not start" >&2; exit 1; }
run 1 "${TLS[@]}" train --zoo --per-category 1 --views 2 --methods esf,vfh --name zoo -q && err_has "UNAUTHENTICATED" "Train without token"
run 1 "${TLS[@]}" --token wrong-token train --zoo --per-category 1 --views 2 --methods esf,vfh --name zoo -q &&
  err_has "UNAUTHENTICATED" "Train with a wrong token"
run 0 "${TLS[@]}" --token "$TOKEN" train --zoo --per-category 1 --views 2 --methods esf,vfh --name zoo -q
GLIMPSE_TOKEN="$TOKEN" run 0 "${TLS[@]}" train --zoo --per-category 1 --views 2 --methods esf,vfh --name zoo -q  # version 2
run 0 "${TLS[@]}" health
run 0 "${TLS[@]}" models list
run 0 "${TLS[@]}" models show zoo:1
echo "0.1 0.2 0.3" >"$TMP/one.xyz"
for i in $(seq 200); do echo "0.$((i % 10)) 0.$((i / 10 % 10)) 0.$((i % 7))"; done >"$TMP/cloud.xyz"
run 0 "${TLS[@]}" classify --model zoo "$TMP/cloud.xyz"
run 0 "${TLS[@]}" stream --zoo chair --model zoo --rate 0 --chunks 3
run 1 "${TLS[@]}" models set-default zoo:1 && err_has "UNAUTHENTICATED" "SetDefaultModel without token"
run 1 "${TLS[@]}" models delete zoo:2 && err_has "UNAUTHENTICATED" "DeleteModel without token"
run 0 "${TLS[@]}" --token "$TOKEN" models set-default zoo:1
run 0 "${TLS[@]}" --token "$TOKEN" models delete zoo:2
run 0 "${TLS[@]}" models list
grep -q "zoo" "$TMP/out" || fail "zoo:1 is gone"
grep -q "model changes need the bearer token" "$TMP/server-token.log" || fail "the start line does not say a token is needed"
grep -q "code=UNAUTHENTICATED" "$TMP/server-token.log" || fail "refusals are not logged"
stop_server

# A token given on the command line and by the environment works the same way.
GLIMPSE_AUTH_TOKEN="$TOKEN" start_server token-env || { echo "server did not start" >&2; exit 1; }
run 1 models delete nothing && err_has "UNAUTHENTICATED" "DeleteModel without token (plaintext, env token)"
run 1 --token "$TOKEN" models delete nothing && err_has "NOT_FOUND" "DeleteModel with the token"
stop_server

# ---- the token never reaches a log ----
for log in "$TMP"/server-*.log; do
  if grep -qF "$TOKEN" "$log"; then fail "$log contains the token"; fi
  if grep -qF "wrong-token" "$log"; then fail "$log contains a presented token"; fi
done

if ((FAILURES > 0)); then
  echo "$FAILURES security checks failed" >&2
  exit 1
fi
echo "all security checks passed"
