#!/usr/bin/env bash
# The dashboard's front-end checks: ESLint and the TypeScript type check (JSDoc, against the
# API types generated from the OpenAPI document) of services/web/static/js.
#
#   services/web/check_frontend.sh
#
# Installs the pinned tools of package-lock.json into node_modules/ (npm ci) when it is
# missing or was installed from another lock file; needs node and npm (Node 20 or newer) and
# the npm registry on first run. Exits non-zero when a check fails.
# Whether api_types.d.ts is current is a pytest test (tests/web/test_api_types_current.py).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/../.."

for tool in node npm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "check_frontend: $tool is not installed (Node 20 or newer is needed)" >&2
    exit 2
  fi
done

# The lock file node_modules/ was installed from, by content (a checkout changes mtimes).
STAMP=node_modules/.legopt-lock.sha256
lock_hash() {
  node -e 'const c = require("crypto"), fs = require("fs");
    process.stdout.write(c.createHash("sha256").update(fs.readFileSync("package-lock.json")).digest("hex"));'
}
want="$(lock_hash)"
if [[ ! -d node_modules || ! -f "$STAMP" || "$(cat "$STAMP")" != "$want" ]]; then
  echo "check_frontend: npm ci (node_modules is missing or stale)"
  npm ci --no-audit --no-fund
  printf '%s' "$want" >"$STAMP"
fi

echo "check_frontend: eslint"
npx --no -- eslint --max-warnings 0 --cache --cache-location node_modules/.cache/eslint/ \
  services/web/static/js eslint.config.js
echo "check_frontend: tsc"
npx --no -- tsc -p tsconfig.json
echo "check_frontend: ok"
