#!/usr/bin/env bash
# Rebuild services/web/static/vendor/ from the npm registry (run by hand when a version changes;
# the built files are committed, so neither CI nor a user needs npm or the network).
#   plotly.js-gl3d-dist-min  the plots (2-D scatter/lines and 3-D scatter for three objectives)
#   swagger-ui-dist          the OpenAPI page at /api/v1/docs
# `npm pack` fetches exactly these versions; the integrity of each tarball is checked by npm.
set -euo pipefail
PLOTLY=3.7.0
SWAGGER=5.35.0
here="$(cd "$(dirname "$0")" && pwd)"
out="$here/static/vendor"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm pack --silent "plotly.js-gl3d-dist-min@$PLOTLY" "swagger-ui-dist@$SWAGGER" >/dev/null
mkdir plotly swagger
tar xzf "plotly.js-gl3d-dist-min-$PLOTLY.tgz" -C plotly
tar xzf "swagger-ui-dist-$SWAGGER.tgz" -C swagger
rm -rf "$out"
mkdir -p "$out/swagger-ui"
cp plotly/package/plotly-gl3d.min.js "$out/plotly-gl3d.min.js"
cp plotly/package/LICENSE "$out/plotly.LICENSE"
cp swagger/package/swagger-ui-bundle.js swagger/package/swagger-ui.css "$out/swagger-ui/"
cp swagger/package/LICENSE "$out/swagger-ui/LICENSE"
# the bundles' source-map comments point at files we do not ship
sed -i '/^\/\/# sourceMappingURL=/d' "$out/swagger-ui/swagger-ui-bundle.js"
sed -i 's#/\*\# sourceMappingURL=[^*]*\*/##' "$out/swagger-ui/swagger-ui.css"
cat > "$out/VERSIONS" <<V
plotly.js-gl3d-dist-min $PLOTLY
swagger-ui-dist $SWAGGER
V
(cd "$out" && find . -type f ! -name SHA256SUMS | sort | xargs sha256sum > SHA256SUMS)
echo "vendored into $out:"; cat "$out/VERSIONS"
