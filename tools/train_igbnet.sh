#!/usr/bin/env bash
# Reproduces models/igbnet.pt (docs/learning.md, The shipped model): the
# paper's dataset, training with the weak labels masked, then DAgger rounds
# (the learned policy acts, the expert labels, aggregate, retrain). Every
# step resumes: run it again after an interruption and it goes on where it
# stopped. About 12 minutes on 2 cores for round 0, 5 more per DAgger round.
#
# Usage: tools/train_igbnet.sh [WORK_DIR (default data/igbnet)] [ROUNDS (default 0)]
# ROUNDS = 0 gives the shipped model; 2 the DAgger comparison of docs/learning.md.
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-data/igbnet}
rounds=${2:-0}
aia=${AIA:-build/aia}
mkdir -p "$work"

# The paper's recipe: 1500 worlds of 10 robots and 10 targets, 10 steps each.
"$aia" dataset --episodes 1500 --out "$work/d0" --quiet
# Round 0: centred frame (the default), weak labels masked, cosine 1e-3 -> 1e-5.
"$aia" train --data "$work/d0" --out "$work/m0.pt" --weak-weight 0 \
  --epochs 8 --lr 1e-3 --lr-min 1e-5 --resume --quiet
data=("$work/d0")
for r in $(seq 1 "$rounds"); do
  prev="$work/m$((r - 1)).pt"
  # The learned policy acts on fresh worlds; a shadow expert labels it.
  "$aia" dataset --episodes 300 --first-seed $((1000000 + r * 1000000)) \
    --policy igbnet --model "$prev" --max-steps 50 --out "$work/d$r" --quiet
  data+=("$work/d$r")
  "$aia" train --data "${data[@]}" --init "$prev" --out "$work/m$r.pt" \
    --weak-weight 0 --epochs 3 --lr 3e-4 --lr-min 1e-5 --resume --quiet
done
cp "$work/m$rounds.pt" models/igbnet.pt
cp "$work/m$rounds.train.csv" models/igbnet.train.csv
echo "models/igbnet.pt <- $work/m$rounds.pt"
