#!/usr/bin/env bash
# Fails when a core stage includes a later stage's header. core/ is one folder per stage in the order the
# data flows: io -> views -> geometry -> features -> learning -> session. A file of stage k (its header
# under core/include/glimpse/<stage>/ or its source under core/src/<stage>/) may include the foundation
# headers (glimpse/*.h), its own stage and the stages before it; never a later stage, the lab
# (glimpse/lab/) or the service. The foundation headers include no stage at all.
set -euo pipefail
core="${1:?usage: check_core_layers.sh CORE_DIR}"
stages=(io views geometry features learning session)
rank() {
  local i
  for i in "${!stages[@]}"; do [[ "${stages[$i]}" == "$1" ]] && { echo "$i"; return; }; done
  echo -1
}
bad=0
checked=0
while IFS= read -r file; do
  rel="${file#"$core"/}"
  case "$rel" in
    include/glimpse/*/*) stage="${rel#include/glimpse/}"; stage="${stage%%/*}" ;;
    include/glimpse/*) stage="" ;;  # a foundation header
    src/*/*) stage="${rel#src/}"; stage="${stage%%/*}" ;;
    *) stage="" ;;
  esac
  own=-1
  if [[ -n "$stage" ]]; then
    own=$(rank "$stage")
    if (( own < 0 )); then echo "check_core_layers: $rel: '$stage' is not a stage (${stages[*]})" >&2; bad=1; continue; fi
  fi
  while IFS= read -r inc; do
    target="${inc#glimpse/}"
    [[ "$target" == */* ]] || continue  # a foundation header
    dep="${target%%/*}"
    dep_rank=$(rank "$dep")
    if (( dep_rank < 0 )); then
      echo "check_core_layers: $rel includes \"$inc\", which is no core stage" >&2; bad=1
    elif (( dep_rank > own )); then
      echo "check_core_layers: $rel (${stage:-foundation}) includes \"$inc\", of the later stage '$dep'" >&2; bad=1
    fi
  done < <(sed -nE 's/^[[:space:]]*#[[:space:]]*include[[:space:]]+"([^"]+)".*/\1/p' "$file" |
           sed -E 's#^(io|views|geometry|features|learning|session)/#glimpse/\1/#')
  checked=$((checked + 1))
done < <(find "$core/include" "$core/src" -type f \( -name '*.h' -o -name '*.cpp' \) | sort)
(( checked > 0 )) || { echo "check_core_layers: no files under $core" >&2; exit 1; }
(( bad == 0 )) || exit 1
echo "check_core_layers: $checked files, each includes only its own stage and the stages before it (${stages[*]})"
