#!/usr/bin/env bash
# Vendors three.js (MIT, https://threejs.org) into the studio: the module build and the few
# addons the page uses, fetched once from the npm registry by whoever updates it. The addons
# import the bare specifier 'three'; without a bundler or an import map (an inline script the
# page's content policy forbids) the browser cannot resolve it, so it is rewritten to the
# vendored module's relative path. Nothing else is changed.
#
#   bash studio/web/vendor/three/update.sh 0.187.0
set -euo pipefail
version="${1:?give the three.js version, e.g. 0.187.0}"
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
curl -sSfL "https://registry.npmjs.org/three/-/three-$version.tgz" -o "$work/three.tgz"
tar xzf "$work/three.tgz" -C "$work"
p="$work/package"
cp "$p/LICENSE" "$here/LICENSE"
cp "$p/build/three.module.js" "$p/build/three.core.js" "$here/"
for f in controls/OrbitControls.js loaders/GLTFLoader.js utils/BufferGeometryUtils.js utils/SkeletonUtils.js; do
    mkdir -p "$here/addons/$(dirname "$f")"
    sed "s#from 'three';#from '../../three.module.js';#" "$p/examples/jsm/$f" > "$here/addons/$f"
done
echo "$version" > "$here/VERSION"
echo "three.js $version vendored into $here"
