#!/usr/bin/env bash
# Command 1 of the README: install, build, and run the demo on the bundled data. Its centrepiece
# is a 5 cm scalpel incision in the bundled liver CT segmentation.
# Outputs go to ./out/demo (or $DEMO_OUT).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
out=${DEMO_OUT:-$root/out/demo}
bash "$root/scripts/build.sh"
vox="$build/src/app/voxsculpt"
data="$root/data"
mkdir -p "$out"

step() { printf '\n== %s\n' "$*"; }

step "Liver CT segmentation (INRIMAGE-4): label 255 -> OpenVDB"
"$vox" import "$data/liver.inr.gz" --label 255 -o "$out/liver.vdb"
"$vox" info --json "$out/liver.vdb" > "$out/liver-info.json"
"$vox" info "$out/liver.vdb"

step "Cutting: a 5 cm scalpel incision in the liver (level 4, separating faces, 150 frames)"
"$vox" run "$data/scenes/liver_incision.json" --out "$out/run-liver-incision"
"$vox" info "$out/run-liver-incision/final.obj"

step "Cutting: a hanging cylinder cut through; the lower piece falls away"
"$vox" run "$data/scenes/cylinder_cut.json" --out "$out/run-cylinder-cut"

step "Dynamic Branched Grid of the liver: levels 0 to 5"
"$vox" grid "$out/liver.vdb" --levels 5
"$vox" grid "$out/liver.vdb" --levels 5 --json > "$out/liver-grid.json"

step "The liver's marching-cubes surface, in world millimetres"
"$vox" export "$out/liver.vdb" -o "$out/liver-surface.ply"
"$vox" export "$out/liver.vdb" -o "$out/liver-surface.obj"

step "Closed mesh (elephant.off) voxelised through OpenVDB"
"$vox" import "$data/elephant.off" --scale 100 --voxel-size 1 -o "$out/elephant.vdb"

step "Open scan mesh with holes (lion.off) voxelised by generalized winding number"
"$vox" import "$data/lion.off" -o "$out/lion.vdb"

step "Phantoms"
"$vox" phantom beam -o "$out/beam.vdb"
"$vox" phantom utube -o "$out/utube.vdb"
"$vox" phantom cylinder -o "$out/cylinder.vdb"

step "The U-tube branches at level 3 (a cell holding both legs gets two superimposed elements)"
"$vox" grid "$out/utube.vdb" --levels 3

step "Scene files"
for scene in "$data"/scenes/*.json; do
  "$vox" check "$scene" > "$out/$(basename "$scene" .json)-check.txt"
  echo "checked $(basename "$scene"): $(sed -n 2p "$out/$(basename "$scene" .json)-check.txt")"
done

step "Simulation: a soft cantilever swinging under gravity (implicit Euler, 50 frames)"
"$vox" run "$data/scenes/beam.json" --frames 50 --out "$out/run-beam"

step "Simulation: a clay slab under two weights, plastic, its right half wet (100 frames)"
"$vox" run "$data/scenes/clay.json" --frames 100 --out "$out/run-clay"


step "Outputs"
ls -l "$out"
echo "demo outputs are in $out"
