#!/usr/bin/env bash
# Fails when the core library references any gRPC, Protobuf or SQLite symbol.
set -euo pipefail
lib="$1"
[[ -f "$lib" ]] || { echo "check_core_deps: no such library: $lib" >&2; exit 1; }
symbols=$(nm -C "$lib" 2>/dev/null | grep -E ' [UTtWw] ' || true)
[[ -n "$symbols" ]] || { echo "check_core_deps: no symbols read from $lib" >&2; exit 1; }
bad=$(grep -E 'grpc|google::protobuf|sqlite3_' <<<"$symbols" || true)
if [[ -n "$bad" ]]; then
  echo "check_core_deps: $lib references service dependencies:" >&2
  head -n 20 <<<"$bad" >&2
  exit 1
fi
echo "check_core_deps: $(wc -l <<<"$symbols") symbols in $(basename "$lib"), none from gRPC/Protobuf/SQLite"
