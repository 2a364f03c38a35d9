#!/usr/bin/env bash
# The spine FE benchmark's L2 (Walle, Matheson & Boyd 2025) by the direct route: its label
# map meshed voxel by voxel (bone and pads), its density image mapped with the benchmark's
# recipe, its compression test solved by CalculiX. See docs/validation.md.
#
#   ATLASMESH_DATA=../shared/data bash examples/spine_benchmark.sh [OUT]
#
# Needs a release build (cargo build --release) and CalculiX (ccx) on the PATH; about a
# minute and 4 GB of memory on 2 cores. Ends with the line `direct: N N/mm`.
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
python3 - "$out/direct/report.json" <<'PY'
import json, sys
print(f"direct: {json.load(open(sys.argv[1]))['solve']['stiffness_n_per_mm']:.0f} N/mm")
PY
