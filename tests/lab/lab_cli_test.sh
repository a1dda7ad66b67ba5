#!/usr/bin/env bash
# glimpse-lab end to end.
#   lab_cli_test.sh LAB zoo            the paper preset and the keypoint ablation on a tiny zoo; flag errors
#   lab_cli_test.sh LAB shrec DIR      the paper preset on a reduced SHREC 2007 protocol, with floors just
#                                      under the measured figures (exit 77 = skipped when DIR is absent)
set -uo pipefail
LAB=$1
MODE=$2
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
FAILURES=0
fail() {
  echo "FAIL: $*" >&2
  FAILURES=$((FAILURES + 1))
}
# run EXPECTED_RC args...: runs glimpse-lab (bounded), checks the exit code.
run() {
  local expected=$1
  shift
  timeout 500 "$LAB" "$@" >"$TMP/out" 2>"$TMP/err"
  local rc=$?
  ((rc == expected)) || { fail "glimpse-lab $* exited $rc, expected $expected; stderr: $(tail -c 1500 "$TMP/err")"; return 1; }
}
has() { grep -qE -- "$2" "$1" || fail "$(basename "$1") lacks /$2/"; }

if [[ $MODE == zoo ]]; then
  # Flag errors say which flag and what it takes.
  run 2 eval --zoo 3 --preset nonsense --out "$TMP/x" && has "$TMP/err" "--preset must be 'paper'"
  run 2 eval --zoo 3 --keypoint-response corner --out "$TMP/x" && has "$TMP/err" "--keypoint-response must be lambda-min or harris"
  run 2 eval --zoo 3 --boundary-radius 0 --out "$TMP/x" && has "$TMP/err" "--boundary-radius must be positive"
  run 2 eval --zoo 3 --min-neighbours 4 --out "$TMP/x" && has "$TMP/err" "--min-neighbours must be at least 6"
  run 2 eval --zoo 3 --methods vfh,ush --keypoint-ablation --out "$TMP/x" && has "$TMP/err" "needs bok, bog or kgh"
  run 2 eval --zoo 3 --hold-out dragon --out "$TMP/x" && has "$TMP/err" "--hold-out: no object of category 'dragon' \(categories: chair, fourleg"
  run 2 eval --zoo 3 --hold-out human,chair,table,mechanic --out "$TMP/x" && has "$TMP/err" "at least two learnt categories must remain"
  run 2 eval --leave-one-out zoo:3 --out "$TMP/x" && has "$TMP/err" "--leave-one-out needs at least two sources"
  run 2 eval --leave-one-out zoo:3,"$TMP/dragons" --also-train zoo:5 --out "$TMP/x" &&
    has "$TMP/err" "--leave-one-out zoo:3,.*dragons \(testing zoo:3\): --test: zoo:3 is named already \(--also-train\)"
  run 105 eval --zoo 3 --poses upright --out "$TMP/x" && has "$TMP/err" "--poses: upright not in \{dataset,given\}"
  # What would make the figures wrong is refused before the run, not found after it (or never).
  run 2 eval --zoo 3 --views 0 --out "$TMP/x" && has "$TMP/err" "--views takes 1-6"
  run 2 eval --zoo 3 --views 10 --out "$TMP/x" && has "$TMP/err" "--views takes 1-6"
  run 2 eval --zoo 3 --stages full,20%,full --out "$TMP/x" && has "$TMP/err" "--stages names full twice"
  run 2 eval --zoo 3 --stages infkp --out "$TMP/x" && has "$TMP/err" "--stages takes full, Nkp and N% items"
  run 2 eval --zoo 3 --size-blind ush,bogus --out "$TMP/x" && has "$TMP/err" "--size-blind: .*bogus"
  run 2 eval --zoo 3 --unknown zoo:2 --out "$TMP/x" && has "$TMP/err" "go with --data or --train"
  run 2 eval --data zoo:3 --also-train zoo:3 --out "$TMP/x" && has "$TMP/err" "--also-train: zoo:3 is named already \(--data\)"
  : >"$TMP/afile"
  run 2 eval --zoo 3 --out "$TMP/afile" && has "$TMP/err" "--out: cannot use"
  mkdir -p "$TMP/dragons/dragon"
  printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' >"$TMP/dragons/dragon/a.off"
  run 2 eval --train zoo:2 --test "$TMP/dragons" --out "$TMP/x" && has "$TMP/err" "categories no training source holds: dragon"
  # views: a mesh of no vertices, and a count with junk after it.
  printf 'OFF\n0 0 0\n' >"$TMP/empty.off"
  run 1 views "$TMP/empty.off" --out "$TMP/v" && has "$TMP/err" "no vertices, nothing to view"
  run 2 views "$TMP/dragons/dragon/a.off" --points 10abc --out "$TMP/v" && has "$TMP/err" "--points must be 'vertices' or a positive count, not '10abc'"
  # compare: paired runs' decisions.csv. Before: 10 objects x 2 views right at full; after: object 0 wrong
  # in both views, object 1 right in the one view it had wrong (95 -> 90 %). An unknown view is left out.
  mkdir -p "$TMP/cmp"
  {
    echo "fold,object,view,stage,method,truth,winner,novelty"
    for o in 0 1 2 3 4 5 6 7 8 9; do for v in 0 1; do echo "0,zoo:chair/$o,$v,full,fusion,chair,chair,1.5"; done; done
    echo "0,psb-other:bed/b,0,full,fusion,unknown:bed,chair,9"
  } | sed 's|zoo:chair/1,1,full,fusion,chair,chair|zoo:chair/1,1,full,fusion,chair,table|' >"$TMP/cmp/before.csv"
  sed -e 's|zoo:chair/0,\([01]\),full,fusion,chair,chair|zoo:chair/0,\1,full,fusion,chair,human|' \
      -e 's|zoo:chair/1,1,full,fusion,chair,table|zoo:chair/1,1,full,fusion,chair,chair|' "$TMP/cmp/before.csv" >"$TMP/cmp/after.csv"
  if run 0 compare "$TMP/cmp/before.csv" "$TMP/cmp/after.csv"; then
    has "$TMP/out" "^1 pair of runs"
    has "$TMP/out" "^\| fusion \| full \| 20 \| 10 \| 95\.0 \| 90\.0 \| -5\.0 \| -[0-9.]+ to [-+][0-9.]+ \| 1 \| 2 \|$"
  fi
  cut -d, -f1-7 "$TMP/cmp/before.csv" | sed 's/$/\r/' >"$TMP/cmp/crlf.csv"  # saved on Windows, winner last
  if run 0 compare "$TMP/cmp/crlf.csv" "$TMP/cmp/after.csv"; then
    has "$TMP/out" "^\| fusion \| full \| 20 \| 10 \| 95\.0 \| 90\.0 \| -5\.0 \|"
  fi
  run 2 compare "$TMP/cmp/before.csv" && has "$TMP/err" "compare takes runs in pairs"
  # A pair is one draw of views: runs of two seeds, or of two view counts, are refused.
  mkdir -p "$TMP/cmp/s42" "$TMP/cmp/s7"
  cp "$TMP/cmp/before.csv" "$TMP/cmp/s42/decisions.csv" && cp "$TMP/cmp/after.csv" "$TMP/cmp/s7/decisions.csv"
  echo '| seed (`--seed`) | 42 | – |' >"$TMP/cmp/s42/report.md"
  echo '| seed (`--seed`) | 7 | – |' >"$TMP/cmp/s7/report.md"
  run 1 compare "$TMP/cmp/s42" "$TMP/cmp/s7" && has "$TMP/err" "drew with seeds 42 and 7"
  grep -v ',1,full,' "$TMP/cmp/after.csv" >"$TMP/cmp/oneview.csv"
  run 1 compare "$TMP/cmp/before.csv" "$TMP/cmp/oneview.csv" && has "$TMP/err" "has 2 views of zoo:chair/0 .* has 1"
  run 1 compare "$TMP/cmp/before.csv" "$TMP/cmp/nothing.csv" && has "$TMP/err" "nothing.csv: cannot read"
  cut -d, -f1-6 "$TMP/cmp/before.csv" >"$TMP/cmp/nowinner.csv"
  run 1 compare "$TMP/cmp/before.csv" "$TMP/cmp/nowinner.csv" && has "$TMP/err" "nowinner.csv: no column 'winner'"
  # --pick-objects: N objects per category drawn by the seed; --poses given: no object turned.
  # (and --export-histograms: what every fold's model decides on, as CSV)
  # (its size-blind re-run, of USH alone, must not overwrite them: VFH rows stay)
  if run 0 eval --zoo 5 --pick-objects 2 --poses given --views 2 --methods ush,vfh --stages full --stream-chunk 0 \
      --size-blind ush --matrix none --export-histograms "$TMP/hist" --out "$TMP/pick"; then
    has "$TMP/pick/report.md" "2 objects per category drawn by seed 42\) \(10 objects: human 2, chair 2, table 2, mechanic 2, fourleg 2\)"
    grep -q "turned to a random pose" "$TMP/pick/report.md" && fail "--poses given: the report says objects were turned"
    # Drawn, not the first two of each category (seed 42 draws human 3 and 4, chair 3 and 4, ...).
    picked=$(cut -d, -f2 "$TMP/pick/decisions.csv" | grep / | sort -u | tr '\n' ' ')
    [[ $picked == "chair/3 chair/4 fourleg/2 fourleg/3 human/3 human/4 mechanic/1 mechanic/3 table/0 table/3 " ]] ||
      fail "--pick-objects 2 --seed 42 picked $picked"
  fi
  # --export-histograms: one file per fold; its test rows are that fold's tested views (2 objects x 2
  # views, stage full), its training rows the other folds' objects only; USH rows hold 152 values.
  for k in 0 1 2 3 4; do
    F="$TMP/hist/fold$k.csv"
    [[ -s $F ]] || { fail "--export-histograms wrote no $F"; continue; }
    [[ $(head -1 "$F") == "set,category,object,view,stage,keypoints,method,histogram..." ]] || fail "$F header: $(head -1 "$F")"
    tested=$(awk -F, -v k=$k '$1 == k && $5 == "ush" {print $2}' "$TMP/pick/decisions.csv" | sort -u | tr '\n' ' ')
    exported=$(awk -F, '$1 == "test" {print $3}' "$F" | sort -u | tr '\n' ' ')
    [[ -n $tested && $tested == "$exported" ]] || fail "fold $k: decisions test '$tested', the export '$exported'"
    (($(awk -F, '$1 == "test" && $5 == "full" && $7 == "ush"' "$F" | wc -l) == 4)) || fail "fold $k: not 4 test rows"
    learnt=$(awk -F, '$1 ~ /^train/ {print $3}' "$F" | sort -u | tr '\n' ' ')
    for o in $tested; do [[ " $learnt" == *" $o "* ]] && fail "fold $k learns its tested object $o"; done
    (($(awk -F, '$1 ~ /^train/' "$F" | wc -l) >= 16)) || fail "fold $k: fewer than 16 training rows (8 objects x 2 views)"
    bad=$(awk -F, 'NR > 1 && $7 == "ush" && NF != 7 + 152' "$F" | wc -l)
    ((bad == 0)) || fail "fold $k: $bad rows without 152 USH values"
    (($(awk -F, '$1 == "test" && $7 == "vfh"' "$F" | wc -l) == 4)) || fail "fold $k: not 4 VFH test rows (overwritten?)"
  done
  touch "$TMP/plain"
  run 2 eval --zoo 3 --export-histograms "$TMP/plain/sub" --out "$TMP/x" && has "$TMP/err" "--export-histograms: cannot create .*plain/sub"
  # --hold-out: a learnt category tested as unknown, the open-set section from known data alone.
  if run 0 eval --zoo 4 --quick --views 2 --methods fusion --stages full --stream-chunk 0 --size-blind none --matrix none \
      --hold-out fourleg --out "$TMP/ho"; then
    R="$TMP/ho/report.md"
    has "$R" "held out as unknown: fourleg"
    has "$R" "## Open set"
    has "$R" "^\| full \| [01]\.[0-9]+ \|"
    has "$R" "^\| fourleg \| [0-9]+ \|"
    has "$R" "\| 32 / 8 \|$"  # 4 learnt categories x 4 objects x 2 views known, 4 fourlegs x 2 views unknown
    has "$R" "2000 resamples of the 16 tested objects"  # the held-out fourlegs are not among them
    has "$R" "^\| Fusion \| [0-9]+\.[0-9]-[0-9]+\.[0-9] \|$"
  fi
  # The preset: the paper's protocol and decision, written in the report; the ablation beside it.
  if run 0 eval --zoo 3 --views 2 --preset paper --quick --keypoint-ablation --out "$TMP/zoo"; then
    R="$TMP/zoo/report.md"
    has "$R" "\| object cloud \(\`--points\`\) \| mesh vertices"
    has "$R" "one K-means centre per category|nearest centre"
    has "$R" "L1 on the histograms \(BoG reduced to 65 dims\)"
    has "$R" "divided by their count up to 25 keypoints"
    has "$R" "rho1 uncapped; each claims rho1"
    has "$R" "## Keypoint ablation"
    has "$R" "\| rho1 <= 8 r \(full views [0-9.]+ kp"
    has "$R" "\| Harris response \(local maxima\)"
    has "$R" "\(paper Table 1\)"
    has "$TMP/out" "^BoK +[0-9.]+ \(89\)"
    # Every ablation row has numbers or says why it failed.
    rows=$(grep -cE "^\| [^|*]+ \| (BoK|BoG|KGH) \|" "$R")
    ((rows >= 30)) || fail "the keypoint ablation has $rows rows, expected >= 30"
  fi
  # A flag given on the command line wins over the preset.
  if run 0 eval --zoo 3 --preset paper --quick --points 1500 --methods bok --matrix none --out "$TMP/zoo2"; then
    has "$TMP/zoo2/report.md" "1500 area-weighted surface samples"
  fi
elif [[ $MODE == shrec ]]; then
  DIR=$3
  if [[ ! -d $DIR ]]; then
    echo "SKIP: SHREC 2007 not found at $DIR (the paper preset test needs ../shared/data/shrec07)"
    exit 77
  fi
  # 10 objects per category, 3 views, seed 42, the preset as shipped.
  if run 0 eval --data "$DIR" --preset paper --max-objects 10 --views 3 --out "$TMP/shrec"; then
    R="$TMP/shrec/report.md"
    cat "$TMP/out"
    acc() { awk -v m="$1" -v col="$2" '$1 == m { print $col }' "$TMP/out"; }
    ge() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a >= b) }' || fail "$3: $1 < $2"; }
    # Fields: method, full, (paper), 10kp, (paper), 25kp, (paper), 55kp, 10%, (paper), 20%, (paper).
    # 150 test views: one is 0.67 points.
    ge "$(acc BoK 2)" 71 "BoK full"     # measured 72.7 (paper 89)
    ge "$(acc BoK 4)" 61 "BoK 10 kp"    # measured 62.7 (paper 64)
    ge "$(acc VFH 2)" 73 "VFH full"     # measured 74.7 (paper 64)
    # Keypoint stages are real stages: full views with >= 25 keypoints.
    share=$(grep -E "^\| 25kp \| [0-9]+ \| [0-9.]+ \|" "$R" | awk -F'|' '{ gsub(/ /, "", $4); print $4 }')
    echo "full views with >= 25 keypoints: ${share:-none} %"
    ge "${share:-0}" 91 "full views with >= 25 keypoints, %"  # measured 92.7 (issue 19's target: 80)
  fi
  # The paper's tables as their figures suggest they were taken (k/18: 3 objects x 6 views per category),
  # trained and tested on the same objects: the report must say the figure is not a held-out one.
  if run 0 eval --train "$DIR" --test "$DIR" --preset paper --pick-objects 3 --stages full,10kp,25kp \
      --out "$TMP/resub"; then
    cat "$TMP/out"
    has "$TMP/resub/report.md" "the tested objects were learnt too"
    has "$TMP/out" "tested on 15 objects of .* \(learnt too: resubstitution, not a held-out figure\):"
    ge "$(acc BoK 2)" 76 "BoK full, 3 objects per category learnt and tested"  # measured 77.8 (paper 89; 90 views: 1.1 points each)
  fi
  # Leave one source out: SHREC tested by a model of the zoo, the zoo by a model of SHREC; a report each
  # and the table over both (3 objects per category, one view each).
  # psb-other's classes, when present, are tested as unknown beside each source.
  OTHER=$(dirname "$DIR")/psb-other
  UNKNOWN=()
  [[ -d $OTHER ]] && UNKNOWN=(--unknown "$OTHER")
  if run 0 eval --leave-one-out "zoo:3,$DIR" "${UNKNOWN[@]}" --max-objects 3 --views 1 --methods fusion --stages full \
      --stream-chunk 0 --size-blind none --matrix none --train-sensors none --out "$TMP/loso"; then
    L="$TMP/loso/leave-one-out.md"
    [[ -s $TMP/loso/zoo-3/report.md && -s $TMP/loso/shrec07/report.md ]] || fail "--leave-one-out: a source's report is missing"
    has "$L" "^\| zoo \| shrec07 \| full \| 15 \| 15 \| [0-9.]+ \[[0-9.]+, [0-9.]+\] \| [0-9.]+ \["
    has "$L" "^\| shrec07 \| zoo \| full \| 15 \| 15 \| "
    has "$L" "^\| zoo \| fourleg \| full \| 3 \| "
    if [[ -d $OTHER ]]; then
      has "$L" "^## Open set across sources"
      has "$L" "^\| shrec07 \| full \| [01]\.[0-9]{3} \| [0-9.]+ \| [0-9.]+ \| 15 / 30 \|"
    fi
  fi
else
  echo "unknown mode $MODE" >&2
  exit 2
fi
if ((FAILURES)); then
  echo "$FAILURES failure(s)" >&2
  exit 1
fi
echo "lab $MODE: all checks passed"
