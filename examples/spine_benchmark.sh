#!/usr/bin/env bash
# The spine FE benchmark's L2 (Walle, Matheson & Boyd 2025) by two routes, its compression
# test solved by CalculiX each time (see docs/validation.md):
# - direct: its label map meshed voxel by voxel (bone and pads), its density image mapped
#   with the benchmark's recipe;
# - atlas: an atlas of the shared VerSe L1 vertebrae fitted to the bone's labels, the pads
#   joined to the fitted mesh by a tie, the same recipe integrated over the smooth elements.
#
#   ATLASMESH_DATA=../shared/data bash examples/spine_benchmark.sh [OUT]
#
# Needs a release build (cargo build --release) and CalculiX (ccx) on the PATH; about three
# minutes and 4 GB of memory on 2 cores. Ends with the lines `direct: N N/mm`, `atlas: N N/mm`.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${ATLASMESH_BIN:-$here/../target/release/atlasmesh}"
bench="${ATLASMESH_DATA:?set ATLASMESH_DATA to the shared data folder}/spinefe-benchmark-L2"
out="${1:-spine-benchmark}"

"$bin" voxel-mesh "$bench/sub-verse004_0000_vertebra_21_seg.nii.gz" \
  --part BONE=1,2,3,4 --part PADS=5,6 --format inp --out "$out/voxels"
"$bin" materials --mesh "$out/voxels/sub-verse004_0000_vertebra_21_seg_voxels.inp" \
  --ct "$bench/sub-verse004_0000_vertebra_21_im.nii.gz" \
  --recipe "$here/spine_benchmark/recipe.toml" --load "$here/spine_benchmark/load.toml" \
  --solve --out "$out/direct"

data="$(dirname "$bench")"
subject=sub-verse004_0000_vertebra_21_seg
"$bin" build --register --shapes "$data/verse-L1-vertebrae-3d/raw" --out "$out/atlas/l1.safetensors"
"$bin" fit --atlas "$out/atlas/l1.safetensors" --subjects "$bench/$subject.nii.gz" \
  --label 1,2,3,4 --format inp,vtu --out "$out/fit"
"$bin" voxel-mesh "$bench/$subject.nii.gz" --part PADS=5,6 \
  --join "$out/fit/$subject/${subject}_mesh.inp" --format inp,vtu --out "$out/joined"
"$bin" materials --mesh "$out/joined/${subject}_joined.inp" \
  --ct "$bench/sub-verse004_0000_vertebra_21_im.nii.gz" \
  --recipe "$here/spine_benchmark/atlas_recipe.toml" --load "$here/spine_benchmark/atlas_load.toml" \
  --solve --format inp,vtu,feb --out "$out/atlas-route"

python3 - "$out/direct/report.json" "$out/atlas-route/report.json" <<'PY'
import json, sys
for route, path in zip(["direct", "atlas"], sys.argv[1:]):
    print(f"{route}: {json.load(open(path))['solve']['stiffness_n_per_mm']:.0f} N/mm")
PY
