#!/usr/bin/env bash
# Fails when the server or the client links the lab: a symbol that libglimpse_lab.a defines is defined in
# the binary too, or one of their sources includes a lab header (glimpse/lab/).
#   check_no_lab.sh LAB_LIBRARY SOURCE_DIR BINARY...
set -euo pipefail
lab="${1:?usage: check_no_lab.sh LAB_LIBRARY SOURCE_DIR BINARY...}"
src="${2:?usage: check_no_lab.sh LAB_LIBRARY SOURCE_DIR BINARY...}"
shift 2
(( $# > 0 )) || { echo "check_no_lab: no binary to check" >&2; exit 1; }
[[ -f "$lab" ]] || { echo "check_no_lab: no such library: $lab" >&2; exit 1; }
lab_symbols=$(nm --defined-only "$lab" 2>/dev/null | awk '$2 ~ /^[TW]$/ {print $3}' | sort -u)
[[ -n "$lab_symbols" ]] || { echo "check_no_lab: no symbols read from $lab" >&2; exit 1; }
bad=0
for dir in server client proto; do
  if hits=$(grep -rnE '#[[:space:]]*include[[:space:]]+"glimpse/lab/' "$src/$dir" 2>/dev/null); then
    echo "check_no_lab: $dir/ includes the lab:" >&2
    echo "$hits" >&2
    bad=1
  fi
done
for bin in "$@"; do
  [[ -f "$bin" ]] || { echo "check_no_lab: no such binary: $bin" >&2; exit 1; }
  # Weak symbols (inline functions, templates) may be shared with core; a lab function is strong (T).
  strong=$(nm --defined-only "$bin" 2>/dev/null | awk '$2 == "T" {print $3}' | sort -u)
  [[ -n "$strong" ]] || { echo "check_no_lab: no symbols read from $bin" >&2; exit 1; }
  both=$(comm -12 <(echo "$lab_symbols") <(echo "$strong") | grep -v '^_\?_\?\(init\|fini\|start\)' || true)
  if [[ -n "$both" ]]; then
    echo "check_no_lab: $(basename "$bin") defines $(wc -l <<<"$both") of the lab's functions, e.g.:" >&2
    head -n 5 <<<"$both" | c++filt >&2
    bad=1
  fi
done
(( bad == 0 )) || exit 1
echo "check_no_lab: $# binaries link none of the lab's $(wc -l <<<"$lab_symbols") functions; server/, client/ and proto/ include no lab header"
