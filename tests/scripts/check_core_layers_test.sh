#!/usr/bin/env bash
# check_core_layers.sh fails on a tree where a stage includes a later stage, and passes on one that does not.
set -euo pipefail
check="$(dirname "$0")/check_core_layers.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/include/glimpse/io" "$tmp/include/glimpse/session" "$tmp/src/views"
printf '#pragma once\n#include "glimpse/cloud.h"\n' > "$tmp/include/glimpse/io/files.h"
printf '#pragma once\n#include "glimpse/io/files.h"\n' > "$tmp/include/glimpse/session/session.h"
printf '#include "glimpse/io/files.h"\n' > "$tmp/src/views/a.cpp"
"$check" "$tmp" > /dev/null || { echo "a tree of earlier includes was refused" >&2; exit 1; }
printf '#include "glimpse/session/session.h"\n' > "$tmp/src/views/b.cpp"
if "$check" "$tmp" 2> "$tmp/err"; then echo "views including session passed" >&2; exit 1; fi
grep -q "src/views/b.cpp (views) includes \"glimpse/session/session.h\", of the later stage 'session'" "$tmp/err" ||
  { cat "$tmp/err" >&2; exit 1; }
rm "$tmp/src/views/b.cpp"
printf '#pragma once\n#include "glimpse/views/x.h"\n' > "$tmp/include/glimpse/cloud_extra.h"
if "$check" "$tmp" 2> /dev/null; then echo "a foundation header including a stage passed" >&2; exit 1; fi
echo "check_core_layers_test: a later include is refused, earlier ones pass"
