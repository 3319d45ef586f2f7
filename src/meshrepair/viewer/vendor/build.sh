#!/usr/bin/env bash
# Rebuild three.bundle.min.js from the npm registry (run once when updating three.js; the
# result is vendored, the package never needs node or the network at run time).
#   bash src/meshrepair/viewer/vendor/build.sh [THREE_VERSION]
set -euo pipefail
THREE_VERSION="${1:-0.187.0}"
ESBUILD_VERSION="0.28.2"
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --save-exact "three@${THREE_VERSION}" "esbuild@${ESBUILD_VERSION}" >/dev/null
cp "$here/entry.js" .
npx esbuild entry.js --bundle --format=esm --minify --legal-comments=eof \
  --banner:js="/* three.js ${THREE_VERSION} (npm package 'three'), MIT licence: see LICENSE-three.txt. Bundled with esbuild ${ESBUILD_VERSION} from entry.js by build.sh. */" \
  --outfile="$here/three.bundle.min.js" --log-level=warning
cp node_modules/three/LICENSE "$here/LICENSE-three.txt"
echo "${THREE_VERSION}" > "$here/THREE_VERSION"
sha256sum "$here/three.bundle.min.js"
