#!/usr/bin/env bash
# The documentation a newcomer reads stays readable and current: README.md at most 200 lines, no line
# over 160 characters outside code blocks; no work-history references ("stop" and a number) outside
# docs/notebook.md; every relative link of README.md and docs/*.md names a file that exists.
#   check_docs.sh SOURCE_DIR
set -euo pipefail
src="${1:?usage: check_docs.sh SOURCE_DIR}"
cd "$src"
bad=0
lines=$(wc -l < README.md)
if (( lines > 200 )); then echo "check_docs: README.md has $lines lines (at most 200)" >&2; bad=1; fi
long=$(awk '/^```/ { code = !code; next } !code && length($0) > 160 { print FILENAME ":" NR ": " length($0) " characters" }' README.md)
if [[ -n "$long" ]]; then echo "check_docs: README.md lines over 160 characters outside code blocks:" >&2; echo "$long" >&2; bad=1; fi
history=$(grep -rnE '\b[Ss]tops? [0-9]+' --include='*' README.md docs core server client proto tests deploy Dockerfile \
            CMakeLists.txt 2>/dev/null | grep -v '^docs/notebook.md:' | grep -v '^tests/scripts/check_docs' || true)
if [[ -n "$history" ]]; then echo "check_docs: work-history references outside docs/notebook.md:" >&2; echo "$history" | head -20 >&2; bad=1; fi
for doc in README.md docs/*.md; do
  dir=$(dirname "$doc")
  while IFS= read -r target; do
    path="${target%%#*}"
    [[ -z "$path" || "$path" =~ ^[a-z]+: ]] && continue  # an anchor in the same file, or a URL
    if [[ ! -e "$dir/$path" ]]; then echo "check_docs: $doc links to $target, which does not exist" >&2; bad=1; fi
  done < <(grep -oE '\]\([^)]+\)' "$doc" | sed -E 's/^\]\((.*)\)$/\1/')
done
(( bad == 0 )) || exit 1
echo "check_docs: README.md $lines lines; no history outside docs/notebook.md; every link of README.md and docs/ resolves"
