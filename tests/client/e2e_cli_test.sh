#!/usr/bin/env bash
# End to end: the real glimpse CLI against the real glimpse-server on a loopback port.
#   e2e_cli_test.sh GLIMPSE_BINARY SERVER_BINARY
# Trains on a tiny zoo and on a folder of meshes and clouds, classifies, streams, manages models, and
# checks exit codes and error messages. About 30 s.
set -uo pipefail
GLIMPSE=$1
SERVER=$2
source "$(dirname "$0")/lib_server.sh"

FAILURES=0
OUT="$GLIMPSE_TEST_TMP/out"
ERR="$GLIMPSE_TEST_TMP/err"

fail() {
  echo "FAIL: $*" >&2
  echo "  stdout: $(head -c 2000 "$OUT")" >&2
  echo "  stderr: $(head -c 2000 "$ERR")" >&2
  FAILURES=$((FAILURES + 1))
}

# run EXPECTED_RC glimpse-args...: runs the CLI (bounded), checks its exit code.
run() {
  local expected=$1
  shift
  timeout 120 "$GLIMPSE" "$@" >"$OUT" 2>"$ERR"
  local rc=$?
  if ((rc != expected)); then fail "glimpse $* exited $rc, expected $expected"; return 1; fi
  return 0
}
out_has() { grep -qE -- "$1" "$OUT" || fail "stdout lacks /$1/"; }
err_has() { grep -qE -- "$1" "$ERR" || fail "stderr lacks /$1/"; }
out_lines() { local n; n=$(wc -l <"$OUT"); ((n == $1)) || fail "stdout has $n lines, expected $1"; }

# ---- test data: DIR/<category>/<files> ----
DATA="$GLIMPSE_TEST_TMP/data"
mkdir -p "$DATA/box" "$DATA/blob"
box() {  # an OFF box of sx x sy x sz metres standing on the ground
  awk -v sx="$1" -v sy="$2" -v sz="$3" 'BEGIN {
    print "OFF"; print "8 12 0";
    for (i = 0; i < 8; i++) print (i % 2) * sx, (int(i / 2) % 2) * sy, (int(i / 4) % 2) * sz;
    split("0 1 3,0 3 2,4 6 7,4 7 5,0 4 5,0 5 1,2 3 7,2 7 6,0 2 6,0 6 4,1 5 7,1 7 3", f, ",");
    for (k = 1; k <= 12; k++) print "3", f[k] }'
}
blob() {  # N random points on a sphere of radius 0.3 m resting on the ground
  awk -v seed="$1" -v n="$2" 'BEGIN { srand(seed);
    for (i = 0; i < n; i++) { u = rand() * 6.2832; v = rand() * 2 - 1; r = 0.3 * sqrt(1 - v * v);
      print r * cos(u), r * sin(u), 0.3 + 0.3 * v } }'
}
box 0.5 0.5 0.5 >"$DATA/box/b1.off"
box 0.4 0.6 0.8 >"$DATA/box/b2.off"
box 0.3 0.3 0.9 >"$DATA/box/b3.off"
blob 1 2000 >"$DATA/blob/s1.xyz"
blob 2 2500 >"$DATA/blob/s2.xyz"
blob 3 1800 >"$DATA/blob/s3.xyz"
BOX="$DATA/box/b1.off"
BLOB="$DATA/blob/s2.xyz"

# ---- usage: exit 2, help: exit 0 (no server needed) ----
run 2 --no-such-flag
run 2
run 2 frobnicate
run 2 classify --model tiny
run 2 classify "$BOX" --model tiny --method svm
run 2 classify "$BOX" --model "bad name"
run 2 stream --zoo dragon --model tiny
run 2 stream --model tiny
run 2 train --zoo
run 2 train --name x
run 2 models
run 2 models set-default "tiny:zero"
run 2 health --ca "$GLIMPSE_TEST_TMP/no-such-ca.pem" --tls
run 2 health --ca "$BOX"          # --ca needs --tls
run 2 health --tls --cert "$BOX"  # --cert needs --key
run 0 --help && out_has "stream" && out_has "--server"
for sub in health models train classify stream "models list" "models show" "models delete" "models set-default"; do
  # shellcheck disable=SC2086
  run 0 $sub --help && out_has "Usage"
done

# ---- a server that is not there: exit 1 with the status code name ----
GLIMPSE_SERVER=127.0.0.1:1 run 1 health --timeout 2 && err_has "^glimpse: health 127.0.0.1:1: UNAVAILABLE"

start_server "$SERVER" "$GLIMPSE" || { echo "FAIL: could not start $SERVER" >&2; exit 1; }

run 0 health && out_has "^SERVING$"
run 0 health --token secret-token  # metadata the server may ignore
run 1 health --tls --timeout 3 && err_has "^glimpse: health .*: UNAVAILABLE"  # a plaintext server
run 0 --version && out_has "^glimpse "
run 0 models list && out_has "^no models$"

# ---- train ----
run 0 train --zoo --per-category 2 --name tiny && out_has "^trained tiny:1 \(default\): 5 categories, 60 clouds"
err_has "^train: 100% done"  # stderr is not a terminal: plain progress lines
run 0 train --zoo --per-category 2 --views 2 --methods bok,esf --name tiny --description "second one" -q --json
out_has '"name":"tiny"' && out_has '"version":2' && out_has '"description":"second one"'
[[ -s "$ERR" ]] && fail "train -q wrote to stderr"
run 0 train "$DATA" --name folder --views 2 --methods esf,vfh && out_has "^trained folder:1 \(default\): 2 categories, 9 clouds"
run 1 train "$DATA" --name folder --methods kgh,bok --views 0 --mesh-points 100 -q  # too few keypoints for codebooks
grep -qE "^glimpse: train $DATA: [A-Z_]+: " "$ERR" || fail "train error lacks the status code"

# ---- classify ----
run 0 classify "$BOX" "$BLOB" --model folder && out_has "^model folder:1  method esf$" && out_has "^FILE +WINNER +blob +box"
out_has "^$BOX +box " && out_has "^$BLOB +blob "
run 0 classify "$BOX" "$BLOB" --model tiny:1 --method bok --json && out_lines 2
out_has '"version":1,"method":"bok"' && out_has '"scores":\{"chair":'
run 1 classify "$BOX" --model nope && err_has "^glimpse: classify $BOX: NOT_FOUND: .*nope"
run 1 classify "$BOX" --model tiny:9 && err_has "NOT_FOUND"
# The proto says FAILED_PRECONDITION for a method the model lacks; the client prints whichever it gets.
run 1 classify "$BOX" --model tiny:2 --method kgh && err_has "^glimpse: classify $BOX: (FAILED_PRECONDITION|INVALID_ARGUMENT): .*kgh"
run 1 classify "$GLIMPSE_TEST_TMP/missing.ply" --model tiny && err_has "missing\.ply"
run 1 classify "$GLIMPSE_TEST_TMP/missing.ply" "$BLOB" --model folder && err_has "missing\.ply" && out_has "^$BLOB +blob"
GLIMPSE_MODEL=folder run 0 classify "$BLOB" && out_has "folder:1"

# ---- stream ----
run 0 stream --zoo chair --model tiny:1 --chunks 5 --rate 50 && out_lines 5
out_has "^chunk 1/5 points [0-9]+ (keypoints [0-9]+ )?winner " && out_has "^chunk 5/5 .* settled (yes|no) confidence [0-9.]+$"
run 0 stream "$BOX" --model tiny --chunk-points 1000 --order random --rate 0 --json && out_has '"chunk":1,' && out_has '"model":"tiny","version":2,"method":"(bok|esf)"'
run 0 stream "$DATA/blob/s1.xyz" --model folder --chunks 3 --order sweep --rate 0 && out_lines 3
run 1 stream --zoo human --model nope --rate 0 && err_has "^glimpse: stream --zoo human: NOT_FOUND"
run 1 stream "$GLIMPSE_TEST_TMP/nothing.off" --model tiny && err_has "nothing\.off"

# ---- models ----
run 0 models list && out_lines 4 && out_has "^tiny +2 +\* " && out_has "^folder +1 +\* "
run 0 models show tiny && out_has "^version: +2 \(default\)" && out_has "^description: +second one"
run 0 models set-default tiny:1 && out_has "version 1"
run 0 models show tiny --json && out_has '"version":1' && out_has '"is_default":true'
run 0 classify "$BLOB" --model tiny --json && out_has '"version":1'
run 1 models set-default tiny:7 && err_has "NOT_FOUND"
run 0 models delete tiny:1 && out_has "^deleted tiny version 1$"
run 1 models show tiny:1 && err_has "^glimpse: models show tiny:1: NOT_FOUND"
run 0 models set-default tiny:latest
run 0 models delete tiny && out_has "^deleted tiny version 2$"
run 0 models list tiny && out_has "^no models$"
run 1 models delete tiny && err_has "NOT_FOUND"

if ((FAILURES > 0)); then
  echo "$FAILURES check(s) failed" >&2
  exit 1
fi
echo "all client end-to-end checks passed"
