#!/usr/bin/env bash
# End to end: the real glimpse CLI against the real glimpse-server on a loopback port.
#   e2e_cli_test.sh GLIMPSE_BINARY SERVER_BINARY
# Trains on a tiny zoo, on a folder of meshes and clouds, on a mesh folder with a manifest (up axes and
# sizes) and on one without (--up/--unit); evaluates a model on another folder; classifies several
# files in one batch (JSON errors included, unit warnings, "unknown"); streams a sensorless cloud as it is;
# finds and classifies the objects of a scene's frame (table, JSON, SVG) and follows one through frames;
# manages models; checks exit codes and error messages. About a minute.
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
# Mesh folders of tall and flat boxes: one with a manifest (y up, arbitrary units), one without (y up,
# millimetres: --up y --unit mm), one to evaluate on (metres, z up, other sizes).
MANIFEST="$GLIMPSE_TEST_TMP/manifest" PLAIN="$GLIMPSE_TEST_TMP/plain" EVAL="$GLIMPSE_TEST_TMP/eval"
mkdir -p "$MANIFEST/tall" "$MANIFEST/flat" "$PLAIN/tall" "$PLAIN/flat" "$EVAL/tall" "$EVAL/flat"
box 3 12 3 >"$MANIFEST/tall/t1.off"; box 2 10 3 >"$MANIFEST/tall/t2.off"; box 4 13 4 >"$MANIFEST/tall/t3.off"
box 10 3 8 >"$MANIFEST/flat/f1.off"; box 12 2 9 >"$MANIFEST/flat/f2.off"; box 9 3 10 >"$MANIFEST/flat/f3.off"
printf '# every mesh of this folder stands along +y\nt1,+y\nt2,+y\nt3,+y\nflat/f1,+y\nf2,+y\nflat/f3.off,+y\n' >"$MANIFEST/up_axis.csv"
printf 'tall,height,1.1,1.3\nflat,height,0.25,0.35\n' >"$MANIFEST/sizes.csv"
box 300 1200 300 >"$PLAIN/tall/t1.off"; box 250 1100 300 >"$PLAIN/tall/t2.off"
box 1000 300 800 >"$PLAIN/flat/f1.off"; box 1100 250 900 >"$PLAIN/flat/f2.off"
box 0.35 0.3 1.25 >"$EVAL/tall/e1.off"; box 0.28 0.32 1.15 >"$EVAL/tall/e2.off"
box 0.9 1.0 0.3 >"$EVAL/flat/e3.off"; box 1.05 0.85 0.28 >"$EVAL/flat/e4.off"
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
for sub in health models train classify stream evaluate "models list" "models show" "models delete" "models set-default"; do
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
# 2 objects x 5 categories x (6 ideal views + 6 from each of the recipe's 6 sensor draws), less the
# sensors' views left with too few points to learn (a LiDAR far off)
run 0 train --zoo --per-category 2 --name tiny && out_has "^trained tiny:1 \(default\): 5 categories, 325 clouds"
err_has "^train: 100% done"  # stderr is not a terminal: plain progress lines
err_has "^train: and the same azimuths seen by a simulated depth camera 0.8-4 m, -10-60 deg \(3 draws\); LiDAR 16 beams 5-20 m, 5 deg; LiDAR 32 beams 5-20 m, 5 deg; LiDAR 64 beams 5-20 m, 5 deg"
# The cameras' views are thinned to the median density of every mesh's ideal views, which a first pass
# measures (10 meshes x 6 views), as glimpse-lab thins them to the model's.
err_has "filtered to the ideal views' density \([0-9]+\.[0-9] points per extent\^2, the median over 60 views;"
# Without --methods the model learns the default set: the fusion, its components and the size baseline.
run 0 models show tiny:1 --json && out_has '"methods":\["METHOD_VFH","METHOD_USH","METHOD_SIZE","METHOD_FUSION"\]'
run 0 train --zoo --per-category 2 --views 2 --methods bok,esf --name tiny --description "second one" -q --json
out_has '"name":"tiny"' && out_has '"version":2' && out_has '"description":"second one"'
[[ -s "$ERR" ]] && fail "train -q wrote to stderr"
run 0 train "$DATA" --name folder --views 2 --methods esf,vfh && out_has "^trained folder:1 \(default\): 2 categories, 34 clouds"
run 0 train "$DATA" --name paper-views --views 2 --methods esf,vfh --sensor-views none && out_has "2 categories, 9 clouds"
run 0 models delete paper-views
# A folder of cloud files alone: they go as they are, and nothing is said of meshes' views or cameras.
CLOUDS="$GLIMPSE_TEST_TMP/clouds"
mkdir -p "$CLOUDS/small" "$CLOUDS/large"
cp "$DATA/blob/s1.xyz" "$DATA/blob/s2.xyz" "$CLOUDS/small/"
for k in 1 2; do awk '{ print $1 * 3, $2 * 3, $3 * 3 }' "$DATA/blob/s$k.xyz" >"$CLOUDS/large/l$k.xyz"; done
run 0 train "$CLOUDS" --name clouds --methods esf,vfh && out_has "^trained clouds:1 \(default\): 2 categories, 4 clouds"
err_has "^train: 4 cloud files: \+z up, in metres, sent as they are$"
grep -qE "surface samples|first pass|simulated" "$ERR" && fail "training on cloud files alone spoke of meshes"
# Growing it: a third category, learnt beside the base's (its methods, parameters and kept features).
GROW="$GLIMPSE_TEST_TMP/grow"
mkdir -p "$GROW/huge"
for k in 1 2; do awk '{ print $1 * 9, $2 * 9, $3 * 9 }' "$DATA/blob/s$k.xyz" >"$GROW/huge/h$k.xyz"; done
run 0 train "$GROW" --base clouds && out_has "^trained clouds:2 \(default\): 3 categories, 6 clouds, .*grown from clouds:1$"
err_has "^train: growing clouds:1$"
run 0 models show clouds:2 && out_has "^grown from: +clouds:1$" && out_has "^can grow: +yes"
run 2 train "$GROW" --base clouds --methods vfh  # the base's methods
run 1 train "$GROW" --base nosuch && err_has "^glimpse: train $GROW: --base nosuch: NOT_FOUND"
run 0 models delete clouds
run 2 train "$DATA" --name folder --sensor-views depth:2 && err_has "depth:2"  # a usage error naming the item
run 1 train "$DATA" --name folder --methods kgh,bok --views 0 --mesh-points 100 -q  # too few keypoints for codebooks
grep -qE "^glimpse: train $DATA: [A-Z_]+: " "$ERR" || fail "train error lacks the status code"

# ---- train on mesh folders: the manifest as glimpse-lab reads it, or --up/--unit ----
run 0 train "$MANIFEST" --name boxes --methods ush,vfh,fusion --views 3 --mesh-points 1500 &&
  out_has "^trained boxes:1 \(default\): 2 categories, 104 clouds"  # 6 x 3 views x (ideal + 6 sensors) less sparse ones
err_has "^train: 6 meshes in 2 categories$" && err_has "^train: up: from up_axis.csv"
err_has "^train: size: real-life ranges per category from sizes.csv.*tall height 1.1-1.3 m"
run 0 train "$PLAIN" --name plain --methods ush,vfh,fusion --views 3 --mesh-points 1500 --up y --unit mm &&
  out_has "^trained plain:1 \(default\): 2 categories, 69 clouds"
err_has "^train: up: \+y for every mesh \(--up\)$" && err_has "^train: size: mesh units x 0.001 m \(--unit\)$"
run 0 models show plain --json && out_has '"feature_version":[1-9]' && out_has '"max_extent_m":1\.[0-9]'
out_has '"bok_codebook_size":60'  # the parameters used (a default nobody asked for), not an echo of the request
out_has '"filter_scans":true'
# More training views from other elevations (as glimpse-lab --train-elevations): 3 elevations x 3 views,
# no simulated camera's; a model that classifies what it is sent as it is.
run 0 train "$PLAIN" --name plain-low --methods ush --views 3 --mesh-points 1500 --up y --unit mm --elevations 0,15 \
  --sensor-views none --no-scan-filters && out_has "^trained plain-low:1 \(default\): 2 categories, 36 clouds"
run 0 models show plain-low --json && out_has '"filter_scans":false'
run 2 train "$PLAIN" --name bad --elevations 95
# A folder plus the zoo (the recipe): the zoo adds objects of the folder's categories only.
MIX="$GLIMPSE_TEST_TMP/mix"
mkdir -p "$MIX/chair" "$MIX/table"
# The folder's chair is named as the zoo's first chair is ("chair/0"); they stay two objects.
box 0.45 0.45 0.95 >"$MIX/chair/0.off"; box 1.2 0.8 0.75 >"$MIX/table/t1.off"
run 0 train "$MIX" --zoo --per-category 1 --name mix --methods ush --views 2 --mesh-points 1500 -q &&
  out_has "^trained mix:1 \(default\): 2 categories, 41 clouds"
run 0 train "$MIX" --zoo --per-category 1 --name mix --methods ush --views 2 --mesh-points 1500 &&
  err_has "^train: also the procedural zoo: 1 objects per category of chair, table, upright, real-life size$"
err_has "the median over 8 views;"  # the folder's 2 meshes and the zoo's 2, 2 views each
run 0 models show mix:2 && out_has "^trained on: +[0-9]+ clouds of 4 objects"
run 2 train "$PLAIN" --zoo --name bad && err_has "the zoo has none of them"
run 2 train "$PLAIN" --name bad --up sideways
run 2 train "$PLAIN" --name bad --unit furlong
run 2 train "$PLAIN" --name bad --unit mm --height 2

# ---- evaluate another folder through the service ----
run 0 evaluate "$EVAL" --model boxes --stages full,20 --views 3 --mesh-points 1500 &&
  out_has "^model boxes:1, method fusion: 4 objects of $EVAL, 3 views each \(12 views\)"
out_has "^stage +accuracy +balanced +right/views +calibration error$" &&
  out_has "^full +[0-9.]+ % +[0-9.]+ % +[0-9]+/12 +([0-9.]+|-)$" && out_has "^20% +[0-9.]+ % +[0-9.]+ % +[0-9]+/12 +([0-9.]+|-)$" && out_has "^confusion at full" && out_has "^misclassified at full: "
err_has "^evaluate: 100% \(4/4 objects\)$"  # progress on stderr, plain lines off a terminal
run 0 evaluate "$EVAL" --model boxes --stages full --views 2 --mesh-points 1500 --json -q
/usr/bin/python3 -c 'import json, sys; r = json.load(sys.stdin); s = r["stages"][0]
assert (r["objects"], r["views"], s["stage"], s["total"]) == (4, 8, "full", 8), r
assert 0 <= s["correct"] <= 8 and set(s["confusion"]) == {"flat", "tall"}, r' <"$OUT" || fail "evaluate --json"
run 1 evaluate "$EVAL" --model nope -q && err_has "^glimpse: evaluate $EVAL: NOT_FOUND"
run 2 evaluate "$EVAL" --model boxes --stages 10kp

# ---- classify ----
run 0 classify "$BOX" "$BLOB" --model folder && out_has "^model folder:1  method esf  (scores|probabilities)$" && out_has "^FILE +WINNER +blob +box"
out_has "^$BOX +box " && out_has "^$BLOB +blob "
run 0 classify "$BOX" "$BLOB" --model tiny:1 --method ush --json && out_lines 2
out_has '"version":1,"method":"ush"' && out_has '"scores":\{"chair":'
# A depth camera's frame as PCL writes it (the camera at the origin, +z ahead, -y up): a blob 0.6 m
# across 0.7 m ahead overflows a 10-degree field, and the answer names the four edges it reaches.
KINECT="$GLIMPSE_TEST_TMP/kinect.pcd"
{ printf 'VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1500\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1500\nDATA ascii\n'
  blob 5 1500 | awk '{ print $1, 0.3 - $3, 0.7 + $2 }'; } >"$KINECT"
run 0 classify "$KINECT" --model folder --camera-fov 10x10 --up=-y && out_has "CUT BY FRAME" && out_has "^$KINECT .* top,bottom,left,right "
run 0 classify "$KINECT" --model folder --camera-fov 10x10 --up=-y --json && out_has '"frame_cut":\["top","bottom","left","right"\]'
run 0 classify "$KINECT" --model folder --camera-fov 170x170 --up=-y && grep -q "CUT BY FRAME" "$OUT" && fail "a wide camera cut the blob"
run 1 classify "$BLOB" --model folder --camera-fov 57x43 && err_has "VIEWPOINT"
run 2 classify "$KINECT" --model folder --camera-fov 57 && err_has "HxV"
run 1 classify "$BOX" --model tiny:1 --method bok && err_has "^glimpse: classify $BOX: FAILED_PRECONDITION: .*bok"
run 1 classify "$BOX" --model nope && err_has "^glimpse: classify $BOX: NOT_FOUND: .*nope"
run 1 classify "$BOX" --model tiny:9 && err_has "NOT_FOUND"
# The proto says FAILED_PRECONDITION for a method the model lacks.
run 1 classify "$BOX" --model tiny:2 --method kgh && err_has "^glimpse: classify $BOX: FAILED_PRECONDITION: .*kgh"
run 1 classify "$GLIMPSE_TEST_TMP/missing.ply" --model tiny && err_has "^glimpse: classify $GLIMPSE_TEST_TMP/missing\.ply: NOT_FOUND: "
run 1 classify "$GLIMPSE_TEST_TMP/missing.ply" "$BLOB" --model folder && err_has "missing\.ply" && out_has "^$BLOB +blob"
# Several files go in one ClassifyBatch call; --json prints one object per file, errors included, in
# the same shape for a missing file and a server error.
run 1 classify "$BOX" "$GLIMPSE_TEST_TMP/missing.ply" "$BLOB" "$DATA/blob/s1.xyz" --model folder --json && out_lines 4
grep -q "rpc=ClassifyBatch .*model=folder@1 .*messages=3 .*code=OK" "$GLIMPSE_TEST_TMP/server.log" || fail "no ClassifyBatch call in the server log"
/usr/bin/python3 -c 'import json, sys; rows = [json.loads(l) for l in sys.stdin]
assert [r["file"].rsplit("/", 1)[-1] for r in rows] == ["b1.off", "missing.ply", "s2.xyz", "s1.xyz"], rows
assert rows[1]["error"]["code"] == "NOT_FOUND" and "error" not in rows[0] and rows[2]["winner"] == "blob", rows' <"$OUT" ||
  fail "classify --json rows"
run 1 classify "$BOX" "$BLOB" --model nope --json && out_lines 2
/usr/bin/python3 -c 'import json, sys; rows = [json.loads(l) for l in sys.stdin]
assert all(r["error"]["code"] == "NOT_FOUND" and "nope" in r["error"]["message"] for r in rows), rows' <"$OUT" ||
  fail "classify --json server errors"
# A mesh in millimetres against a model of metre-sized boxes: a warning a person reads.
run 0 classify "$PLAIN/tall/t1.off" --model boxes && err_has "^glimpse: classify $PLAIN/tall/t1.off: warning: the cloud spans 1\.[0-9]+e\+03 m.*millimetres"
run 0 classify "$PLAIN/tall/t1.off" --model boxes --json && out_has '"warning":"the cloud spans'
# "None of these": a 1.2 km box is nothing the model learnt (its size says so, whatever its novelty);
# the winner stays the closest category.
run 0 classify "$PLAIN/tall/t1.off" --model boxes --json &&
  out_has '"unknown":true,"novelty":[0-9.e+]+,"unknown_reason":"size far outside what the model learnt: the cloud spans'
run 0 classify "$PLAIN/tall/t1.off" --model boxes && out_has "^$PLAIN/tall/t1.off +unknown \(closest: (tall|flat) [0-9.]+\) "
out_has "NOVELTY"
run 0 classify "$PLAIN/tall/t1.off" --model boxes --known-acceptance 1 --json && out_has '"novelty":[0-9.e+]+'
run 2 classify "$BOX" --model boxes --known-acceptance 1.5
# (the winner is right; a model of 6 boxes may still find this view novel: the closest category then)
run 0 classify "$PLAIN/tall/t1.off" --model boxes --up y --unit mm --view 2 &&
  out_has "^$PLAIN/tall/t1.off +(tall|unknown \(closest: tall [0-9.]+\)) "
[[ -s "$ERR" ]] && fail "classify in the right unit warned"
run 0 classify "$PLAIN/tall/t1.off" --model boxes --unit mm --whole --json && out_has '"warning":""'
run 2 classify "$BOX" --model boxes --view 2 --whole
run 2 classify "$BOX" --model boxes --known-acceptance 0 && err_has "\(0, 1\]"  # 0 would mean "the model's"
# A cloud file in millimetres: warned, and --unit mm (or --up) places a cloud as it places a mesh.
awk '{ print $1 * 1000, $2 * 1000, $3 * 1000 }' "$BLOB" >"$GLIMPSE_TEST_TMP/blob_mm.xyz"
run 0 classify "$GLIMPSE_TEST_TMP/blob_mm.xyz" --model folder && err_has "warning: the cloud spans .*millimetres"
run 0 classify "$GLIMPSE_TEST_TMP/blob_mm.xyz" --model folder --unit mm && out_has "blob_mm\.xyz +blob "
[[ -s "$ERR" ]] && fail "a cloud given its unit warned"
run 1 classify "$BLOB" --model folder --height 2 && err_has "s2\.xyz: INVALID_ARGUMENT: --height scales meshes"
run 0 classify "$BLOB" --model folder --view 2 && err_has "s2\.xyz: warning: --view and --whole are for meshes"
run 1 classify "$DATA" --model folder && err_has "$DATA: INVALID_ARGUMENT: is a folder, not a file"
# A cloud the server refuses in a batch is named by its file, not by its place among the clouds sent.
{ cat "$BLOB"; echo "1e30 0 0"; } >"$GLIMPSE_TEST_TMP/far.xyz"
run 1 classify "$BLOB" "$GLIMPSE_TEST_TMP/far.xyz" --model folder && out_has "^$BLOB +blob " &&
  err_has "far\.xyz: INVALID_ARGUMENT: xyz: point 2500 has a coordinate beyond"
grep -q "cloud 1:" "$ERR" && fail "a batch's error named the cloud's place, not only its file"
GLIMPSE_MODEL=folder run 0 classify "$BLOB" && out_has "folder:1"

# ---- stream ----
run 0 stream --zoo chair --model tiny:1 --chunks 5 --rate 50 && out_lines 6 && out_has "^final points "
out_has "^chunk 1/5 points [0-9]+ (keypoints [0-9]+ )?winner " && out_has "^chunk 5/5 .* settled (yes|no) confidence [0-9.]+( novelty [0-9.]+)?$"
run 0 stream "$BOX" --model tiny --chunk-points 1000 --order random --rate 0 --json && out_has '"chunk":1,' && out_has '"final":true' && out_has '"model":"tiny","version":2,"method":"(bok|esf)"'
run 0 stream "$DATA/blob/s1.xyz" --model folder --chunks 3 --order sweep --rate 0 && out_lines 4
# A cloud without a sensor streams as it is: all of its 1800 points (a view is cut only when asked).
run 0 stream "$DATA/blob/s3.xyz" --model folder --chunks 3 --rate 0 && out_has "^chunk 3/3 points 1800 "
run 0 stream "$DATA/blob/s3.xyz" --model folder --chunks 3 --rate 0 --view 1 && out_lines 4
grep -q "^chunk 3/3 points 1800 " "$OUT" && fail "stream --view 1 did not cut a view"
# A sensor the file cannot state (a camera-frame scan, VIEWPOINT at the origin) is given by hand.
run 0 stream "$DATA/blob/s3.xyz" --model folder --chunks 3 --rate 0 --sensor 0,0,-2 && out_has "^chunk 3/3 points 1800 "
run 2 stream "$DATA/blob/s3.xyz" --model folder --sensor 0,0 && err_has "X,Y,Z"
run 2 stream "$DATA/blob/s3.xyz" --model folder --sensor 0,0,0 --view 1
run 1 stream "$BOX" --model tiny --sensor 0,0,0 --rate 0 && err_has "sensor is for cloud files"
# A folder of frames, each from its own sensor (here from poses.csv): one chunk per frame, then the final.
FRAMES="$GLIMPSE_TEST_TMP/frames"
mkdir -p "$FRAMES" && cp "$DATA/blob/s1.xyz" "$FRAMES/f10.xyz" && cp "$DATA/blob/s3.xyz" "$FRAMES/f9.xyz"
run 1 stream --frames "$FRAMES" --model folder --rate 0 && err_has "f9\.xyz: a frame needs its sensor position"
printf 'f9.xyz,0,-3,1\nf10.xyz,0,3,1\n' >"$FRAMES/poses.csv"
run 0 stream --frames "$FRAMES" --model folder --rate 0 && out_lines 3 && out_has "^chunk 2/2 " && out_has "^final points "
run 0 stream --frames "$FRAMES" --model folder --rate 0 --chunk-points 1000 --json && out_has '"chunk":4,' && out_has '"final":true'
run 2 stream --frames "$FRAMES" "$DATA/blob/s1.xyz" --model folder
run 2 stream --frames "$FRAMES" --order random --model folder
run 1 stream --zoo human --model nope --rate 0 && err_has "^glimpse: stream --zoo human: NOT_FOUND"

# ---- scenes: a frame of a floor with a box and a blob on it ----
SCENE="$GLIMPSE_TEST_TMP/scene"
mkdir -p "$SCENE/frames"
scene_frame() {  # x y z of a 2 x 2 m floor (2 cm grid), a 0.4 m box at (-0.5, 1), a blob at (0.5, 1.2)
  awk 'BEGIN { for (i = 0; i <= 100; i++) for (j = 0; j <= 100; j++) print -1 + 0.02 * i, 0.02 * j, 0 }'
  awk 'BEGIN { for (i = 0; i <= 40; i++) for (j = 0; j <= 50; j++) {
      print -0.7 + 0.01 * i, 0.8, 0.01 * j; print -0.7 + 0.01 * i, 1.2, 0.01 * j;
      print -0.7, 0.8 + 0.01 * i, 0.01 * j; print -0.3, 0.8 + 0.01 * i, 0.01 * j }
    for (i = 0; i <= 40; i++) for (j = 0; j <= 40; j++) print -0.7 + 0.01 * i, 0.8 + 0.01 * j, 0.5 }'
  blob 7 4000 | awk '{ print $1 + 0.5, $2 + 1.2, $3 }'
}
scene_frame >"$SCENE/frame.xyz"
run 0 scene "$SCENE/frame.xyz" --model folder --sensor 0,-1,1.2 --svg "$SCENE/top.svg" && out_has " 2 objects, 1 planes," \
  && out_has "^1  " && out_has "^2  " && out_has "RANGE_M"
grep -q "<svg" "$SCENE/top.svg" && grep -q ">1 " "$SCENE/top.svg" || fail "scene --svg wrote no labelled top view"
run 0 scene "$SCENE/frame.xyz" --model folder --sensor 0,-1,1.2 --json && out_lines 1 \
  && out_has '"objects":\[\{"object":1,"box_min":' && out_has '"planes":\[\{"normal":\[[-0-9.e]+,[-0-9.e]+,(1|0\.99[0-9]*)\]'
# The same frame on its side (y up): a warning, the objects still found.
awk '{ print $1, -$3, $2 }' "$SCENE/frame.xyz" >"$SCENE/side.xyz"
run 0 scene "$SCENE/side.xyz" --model folder --sensor 0,-1.2,-1 && err_has "warning: .*is \+z up\?"
run 0 scene "$SCENE/side.xyz" --model folder --sensor 0,-1.2,-1 --up y && out_has " 2 objects,"
run 1 scene "$BOX" --model folder && err_has "b1\.off: a mesh"
run 1 scene "$SCENE/frame.xyz" --model nope && err_has "NOT_FOUND"
run 2 scene "$SCENE/frame.xyz" --model folder --cluster-tolerance 0
# Following one object through frames from two sensor positions: every frame says where it is.
cp "$SCENE/frame.xyz" "$SCENE/frames/a.xyz" && cp "$SCENE/frame.xyz" "$SCENE/frames/b.xyz"
printf 'a.xyz,0,-1,1.2\nb.xyz,0.8,-0.8,1.2\n' >"$SCENE/frames/poses.csv"
run 0 stream --frames "$SCENE/frames" --model folder --rate 0 --track=-0.5,1,0.25 && out_lines 3 \
  && out_has "^chunk 1/2 .* target at -0\.50,1\.00,0\.[23][0-9] \(2 objects\)" && out_has "^chunk 2/2 .* target at -0\.50,1\.00"
# A target no frame shows: each frame says so, and the scan ends without a decision.
run 1 stream --frames "$SCENE/frames" --model folder --rate 0 --track 5,5,5 \
  && out_has "^chunk 1/2 .* target not found \(no object within" && err_has "the scan ended without a decision"
run 2 stream "$BLOB" --model folder --track nearest  # frames only
run 1 stream "$GLIMPSE_TEST_TMP/nothing.off" --model tiny && err_has "nothing\.off"
# A scan too small to decide ends in an error, as Classify's does, not in an OK with no answer.
printf '0 0 0\n0.1 0 0\n' >"$GLIMPSE_TEST_TMP/two.xyz"
run 1 stream "$GLIMPSE_TEST_TMP/two.xyz" --model folder --rate 0 && err_has "INVALID_ARGUMENT: the scan ended without a decision"
run 0 stream "$GLIMPSE_TEST_TMP/blob_mm.xyz" --model folder --chunks 2 --rate 0 --unit mm && out_has "^final points .*(winner blob|closest: blob)"
# Without its unit the final decision is unknown by its size, and stderr says why, as classify's warning does.
run 0 stream "$GLIMPSE_TEST_TMP/blob_mm.xyz" --model folder --chunks 2 --rate 0 &&
  out_has "^final points .*winner unknown" && err_has "blob_mm\.xyz: unknown: size far outside what the model learnt: the cloud spans"

# ---- models ----
run 0 models list && out_lines 9 && out_has "^tiny +2 +\* " && out_has "^folder +1 +\* "
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
