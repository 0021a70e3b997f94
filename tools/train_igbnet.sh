#!/usr/bin/env bash
# Reproduces the shipped models (docs/learning.md, The shipped model):
#   models/igbnet.pt        the paper's dataset plus worlds of 20, 40 and 80
#                           robots, weak labels masked (the default policy);
#   models/igbnet_10x10.pt  the paper's dataset alone (10 robots), as the
#                           paper's scalability experiment prescribes;
# then, with ROUNDS > 0, DAgger rounds on the first (the learned policy acts,
# the expert labels, aggregate, retrain). Every step resumes: run it again
# after an interruption and it goes on where it stopped. About 45 minutes on
# 2 cores (datasets 15, training 20 + 10), plus 10 per DAgger round.
#
# Usage: tools/train_igbnet.sh [WORK_DIR (default data/igbnet)] [ROUNDS (default 0)]
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-data/igbnet}
rounds=${2:-0}
aia=${AIA:-build/aia}
mkdir -p "$work"

# The paper's recipe: 1500 worlds of 10 robots and 10 targets, 10 steps each.
"$aia" dataset --episodes 1500 --out "$work/d0" --quiet
# Larger teams in the same 20 x 20 m worlds (every step of an episode is
# kept: missions at 80 robots last a few steps).
"$aia" dataset --size 20x20 --episodes 300 --first-seed 5000000 --out "$work/d0_20" --quiet
"$aia" dataset --size 40x40 --episodes 600 --first-seed 6000000 --out "$work/d0_40" --quiet
"$aia" dataset --size 80x80 --episodes 800 --first-seed 7000000 --out "$work/d0_80" --quiet
data=("$work/d0" "$work/d0_20" "$work/d0_40" "$work/d0_80")

# Both models: centred frame (the default), weak labels masked, cosine
# 1e-3 -> 1e-5 over 8 epochs.
"$aia" train --data "$work/d0" --out "$work/m0_10x10.pt" --weak-weight 0 \
  --epochs 8 --lr 1e-3 --lr-min 1e-5 --resume --quiet
"$aia" train --data "${data[@]}" --out "$work/m0.pt" --weak-weight 0 \
  --epochs 8 --lr 1e-3 --lr-min 1e-5 --resume --quiet

for r in $(seq 1 "$rounds"); do
  prev="$work/m$((r - 1)).pt"
  # The learned policy acts on fresh worlds; a shadow expert labels it.
  base=$((1000000 + r * 1000000))
  "$aia" dataset --episodes 300 --first-seed "$base" --policy igbnet \
    --model "$prev" --max-steps 50 --out "$work/d$r" --quiet
  "$aia" dataset --size 40x40 --episodes 100 --first-seed $((base + 100000)) \
    --policy igbnet --model "$prev" --max-steps 50 --out "$work/d${r}_40" --quiet
  "$aia" dataset --size 80x80 --episodes 100 --first-seed $((base + 200000)) \
    --policy igbnet --model "$prev" --max-steps 50 --out "$work/d${r}_80" --quiet
  data+=("$work/d$r" "$work/d${r}_40" "$work/d${r}_80")
  "$aia" train --data "${data[@]}" --init "$prev" --out "$work/m$r.pt" \
    --weak-weight 0 --epochs 3 --lr 3e-4 --lr-min 1e-5 --resume --quiet
done
cp "$work/m0_10x10.pt" models/igbnet_10x10.pt
cp "$work/m0_10x10.train.csv" models/igbnet_10x10.train.csv
cp "$work/m$rounds.pt" models/igbnet.pt
cp "$work/m$rounds.train.csv" models/igbnet.train.csv
echo "models/igbnet.pt <- $work/m$rounds.pt; models/igbnet_10x10.pt <- $work/m0_10x10.pt"
