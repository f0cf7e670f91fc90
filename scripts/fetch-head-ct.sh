#!/usr/bin/env bash
# Fetches the real head CT the project develops against (data/ct/README.md): the sample skull of
# InVesalius from Debian's invesalius-examples package. Its licence is GPL-2, so it is fetched from
# the registry rather than kept in the repository. Writes OUT/cranium.mhd and OUT/cranium.raw
# (MetaImage: int16 Hounsfield units, 256 x 256 x 108 voxels of 0.957 x 0.957 x 1.5 mm).
# Usage: scripts/fetch-head-ct.sh [OUT]   (default: data/ct)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/data/ct}
if [ -f "$out/cranium.mhd" ] && [ -f "$out/cranium.raw" ]; then
  echo "fetch-head-ct: $out/cranium.mhd is there"
  exit 0
fi
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
echo "fetch-head-ct: downloading invesalius-examples from Debian (19 MB)"
if ! apt-get download -q invesalius-examples >/dev/null 2>&1; then
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -q >/dev/null
  apt-get download -q invesalius-examples >/dev/null || {
    echo "fetch-head-ct: cannot download invesalius-examples (no Debian package index reachable?)" >&2
    exit 1
  }
fi
dpkg-deb -x invesalius-examples_*.deb package
# An InVesalius project is a gzipped tar: main.plist says the volume's shape, type and spacing,
# matrix.dat holds it raw (int16, this machine's byte order when written: little-endian, z y x).
tar -xzf package/usr/share/doc/invesalius-examples/examples/Cranium.inv3
plist=$(find . -name main.plist -not -path "./package/*" | head -1)
matrix=$(dirname "$plist")/matrix.dat
python3 - "$plist" "$out/cranium.mhd" <<'PY'
import plistlib, sys
with open(sys.argv[1], "rb") as f:
    p = plistlib.load(f)
m = p["matrix"]
z, y, x = m["shape"]
sx, sy, sz = p["spacing"]
if m["dtype"] != "int16" or p.get("modality") != "CT":
    sys.exit(f"fetch-head-ct: unexpected project: {m['dtype']} {p.get('modality')}")
with open(sys.argv[2], "w") as f:
    f.write("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
            "CompressedData = False\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = 0 0 0\n"
            f"ElementSpacing = {sx!r} {sy!r} {sz!r}\nDimSize = {x} {y} {z}\n"
            "ElementType = MET_SHORT\nElementDataFile = cranium.raw\n")
print(f"fetch-head-ct: {x} x {y} x {z} voxels of {sx:.4f} x {sy:.4f} x {sz} mm")
PY
cp "$matrix" "$out/cranium.raw.partial"
mv "$out/cranium.raw.partial" "$out/cranium.raw"
echo "fetch-head-ct: wrote $out/cranium.mhd and cranium.raw"
