#!/usr/bin/env bash
# deploy/k8s against the Kubernetes OpenAPI schemas (k8s_schema/check.mjs, npm package
# kubernetes-models, versions pinned in k8s_schema/package-lock.json), then the same check on a copy
# with two type errors, which it must reject.
#   k8s_schema_test.sh WORK_DIR SCHEMA_SOURCE_DIR K8S_DIR
# WORK_DIR keeps node_modules between runs; the first run needs the npm registry (npm ci).
set -euo pipefail
work=$1 src=$2 k8s=$3
mkdir -p "$work"
for f in package.json package-lock.json check.mjs; do cp "$src/$f" "$work/$f"; done
if ! cmp -s "$work/package-lock.json" "$work/node_modules/.installed-lock.json" 2>/dev/null; then
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error) ||
    { echo "FAIL: npm ci of $src/package.json failed (the npm registry is needed once)" >&2; exit 1; }
  cp "$work/package-lock.json" "$work/node_modules/.installed-lock.json"
fi
node "$work/check.mjs" "$k8s"

broken="$work/broken"
rm -rf "$broken" && mkdir -p "$broken" && cp "$k8s"/*.yaml "$broken/"
sed -i 's/^\(\s*\)port: 50051$/\1port: "grpc"/' "$broken/deployment.yaml"
sed -i 's/clusterIP: None/clusterIP: 5/' "$broken/service.yaml"
if out=$(node "$work/check.mjs" "$broken"); then
  echo "FAIL: the schema check accepted a string probe port and a numeric clusterIP" >&2
  exit 1
fi
grep -q "grpc/port must be integer" <<<"$out" || { echo "FAIL: the probe port type error was not reported: $out" >&2; exit 1; }
grep -q "clusterIP must be string" <<<"$out" || { echo "FAIL: the clusterIP type error was not reported: $out" >&2; exit 1; }
echo "k8s schema: the injected type errors are rejected"
