#!/usr/bin/env bash
# Reproduces the shipped models (docs/learning.md, The shipped models):
#   models/igbnet.pt        the default: five channels (the reach channel),
#                           trained on domain-randomized worlds (generated
#                           mazes, offices, corridors and caves, 20 to 40 m,
#                           0 to 120 boxes, 2 to 80 robots, range graphs with
#                           packet loss, sensor ranges 1.5 to 3 m), weak
#                           labels masked;
#   models/igbnet_10x10.pt  the paper's configuration: four channels, the
#                           paper's dataset alone (1500 open worlds of 10
#                           robots), kept so that its results can be repeated.
# With MODELS=learned it also trains models/igbnet_learned.pt, the model
# meant for policy.coordination=none (the network alone; DAgger rounds,
# about 1.5 hours more on 2 cores). With MODELS=all it also trains the ablation's
# four-channel model on the randomized data and the 10-robot-only model
# (the same inputs and worlds, teams of 10 only; the scalability check)
# and the learned model.
#
# Every step resumes: run it again after an interruption and it goes on
# where it stopped. On 2 cores: the data about 20 minutes (two processes),
# the default model about 30 minutes, the paper's 8.
#
# Usage: tools/train_igbnet.sh [WORK_DIR (default data/igbnet)]
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-data/igbnet}
aia=${AIA:-build/aia}
models=${MODELS:-default}
mkdir -p "$work"

ds() {
  local out=$1
  shift
  "$aia" dataset --out "$work/$out" --quiet "$@"
}

# The paper's recipe: 1500 worlds of 10 robots and 10 targets, 20 x 20 m, 30
# boxes, 10 steps each (also the randomized data's open worlds).
ten=(d0)
all=(d0)
ds d0 --episodes 1500 &
(
  # Small and large teams; every seed range is disjoint from aia eval's
  # (0.., selection 5000.., the generalization suite's 931000..) and from
  # each other.
  ds small5 --size 5x5 --keep 20 --episodes 400 --first-seed 21200000 \
    --set "workspace.size=[30,30]" --set workspace.obstacles.random.count=68
  ds small3r --size 3x3 --keep 30 --episodes 300 --first-seed 21300000 \
    --set workspace.obstacles.generator.type=rooms --set "workspace.size=[20,20]"
  ds small3m --size 3x3 --keep 30 --episodes 300 --first-seed 21400000 \
    --set workspace.obstacles.generator.type=maze --set "workspace.size=[20,20]"
  ds small2 --size 2x2 --keep 30 --episodes 300 --first-seed 21500000
  ds comm --episodes 300 --first-seed 21600000 --set communication.mode=range \
    --set communication.range=4 --set communication.packet_loss_lambda=1
  ds sens15 --episodes 150 --first-seed 21700000 --set sensor.range=1.5
  ds sens3 --episodes 150 --first-seed 21800000 --set sensor.range=3
  ds clutter0 --episodes 100 --first-seed 21900000 \
    --set workspace.obstacles.random.count=0
  ds clutter60 --episodes 150 --first-seed 22000000 \
    --set workspace.obstacles.random.count=60
  ds t40 --size 40x40 --episodes 200 --first-seed 22100000 --max-steps 60
  ds t80 --size 80x80 --episodes 200 --first-seed 22200000 --max-steps 40
) &
wait
# Generated structured worlds of 10 robots, and larger workspaces at the
# paper's box density (0.075 per square metre).
k=0
for g in maze rooms corridors cave; do
  for side in 20 30; do
    k=$((k + 1))
    ds "g_${g}_$side" --episodes 150 --first-seed $((20000000 + k * 100000)) \
      --set "workspace.obstacles.generator.type=$g" \
      --set "workspace.size=[$side,$side]" &
    ten+=("g_${g}_$side")
    if ((k % 2 == 0)); then wait; fi
  done
done
ds dens30 --episodes 300 --first-seed 21000000 --set "workspace.size=[30,30]" \
  --set workspace.obstacles.random.count=68 &
ds dens40 --episodes 200 --first-seed 21100000 --set "workspace.size=[40,40]" \
  --set workspace.obstacles.random.count=120 &
wait
ten+=(dens30 dens40 comm sens15 sens3 clutter0 clutter60)
all=("${ten[@]}" small5 small3r small3m small2 t40 t80)
paths() { for d in "$@"; do printf '%s\n' "$work/$d"; done; }
mapfile -t ten_paths < <(paths "${ten[@]}")
mapfile -t all_paths < <(paths "${all[@]}")

# The default: the reach channel (--geodesic), centred frame, weak labels
# masked, cosine 1e-3 -> 1e-5 over 3 epochs, two libtorch threads (about 30
# minutes alone on 2 cores; the thread count is part of the recipe: a
# reduction over two threads does not add in the same order as over one).
"$aia" train --data "${all_paths[@]}" --geodesic --epochs 3 --threads 2 \
  --out "$work/igbnet.pt" --weak-weight 0 --lr 1e-3 --lr-min 1e-5 --resume --quiet
# The paper's configuration (four channels, its dataset alone), as before.
"$aia" train --data "$work/d0" --out "$work/igbnet_10x10.pt" --weak-weight 0 \
  --epochs 8 --lr 1e-3 --lr-min 1e-5 --resume --quiet
if [[ $models == all ]]; then
  # The ablation's four-channel model on the same data, and the 10-robot
  # model (the same inputs and worlds, teams of 10 only).
  "$aia" train --data "${all_paths[@]}" --epochs 3 --threads 2 \
    --out "$work/ablation_4ch.pt" --weak-weight 0 --lr 1e-3 --lr-min 1e-5 --resume --quiet
  "$aia" train --data "${ten_paths[@]}" --geodesic --epochs 3 --threads 2 \
    --out "$work/igbnet_10only.pt" --weak-weight 0 --lr 1e-3 --lr-min 1e-5 --resume --quiet
fi
shipped=(igbnet igbnet_10x10)
if [[ $models == all || $models == learned ]]; then
  # The learned-coordination model (docs/learning.md, Learned coordination):
  # the default model's weights, its reach channel over the whole workspace
  # toward each target's search points and a trail channel (the pixel the
  # robot came from) added, one epoch on the data above; then DAgger rounds:
  # the model alone (policy.coordination=none) acts in 15 kinds of world,
  # the expert labels the states it visits, and the next model is trained on
  # the data above and every round so far. About 25 minutes a round.
  learn() {  # learn OUT INIT DATA...
    local out=$1 init=$2
    shift 2
    "$aia" train --data "$@" --init "$init" --epochs 1 --lr 3e-4 --lr-min 1e-5 \
      --weak-weight 0 --threads 2 --out "$out" --resume --quiet
  }
  "$aia" train --data "${all_paths[@]}" --init "$work/igbnet.pt" --reach-world 1 \
    --search 1 --trail 1 --epochs 1 --lr 3e-4 --lr-min 1e-5 --weak-weight 0 \
    --threads 2 --out "$work/learned0.pt" --resume --quiet
  dagger_paths=()
  rounds=${ROUNDS:-3}
  for ((r = 1; r <= rounds; r++)); do
    actor="$work/learned$((r - 1)).pt"
    base=$((30000000 + r * 1000000))
    dag() {  # dag NAME SEED STEPS ARGS...: the actor alone acts
      local name=$1 seed=$2 steps=$3
      shift 3
      ds "dag$r/$name" --policy igbnet --model "$actor" \
        --set policy.coordination=none --keep 20 --max-steps "$steps" \
        --first-seed "$seed" "$@"
    }
    g=workspace.obstacles.generator.type
    (
      dag maze30 $((base + 100000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=maze
      dag rooms30 $((base + 200000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=rooms
      dag corr30 $((base + 300000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=corridors
      dag cave30 $((base + 400000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=cave
      dag maze40 $((base + 500000)) 300 --episodes 50 --set "workspace.size=[40,40]" --set $g=maze
      dag open10 $((base + 600000)) 200 --episodes 100
      dag rooms40 $((base + 1500000)) 300 --episodes 50 --set "workspace.size=[40,40]" --set $g=rooms
    ) &
    (
      dag rooms20_3 $((base + 700000)) 200 --episodes 100 --size 3x3 --set $g=rooms
      dag maze20_3 $((base + 800000)) 200 --episodes 100 --size 3x3 --set $g=maze
      dag corr20_5 $((base + 900000)) 200 --episodes 100 --size 5x5 --set $g=corridors
      dag cave20_5 $((base + 1000000)) 200 --episodes 100 --size 5x5 --set $g=cave
      dag open2x20 $((base + 1100000)) 200 --episodes 100 --size 2x20
      dag range $((base + 1200000)) 200 --episodes 100 --set communication.mode=range \
        --set communication.range=4 --set communication.packet_loss_lambda=1
      dag dens40 $((base + 1300000)) 150 --episodes 50 --set "workspace.size=[40,40]" \
        --set workspace.obstacles.random.count=120
      dag t40 $((base + 1400000)) 40 --episodes 50 --size 40x40
    ) &
    wait
    for name in maze30 rooms30 corr30 cave30 maze40 open10 rooms40 rooms20_3 \
      maze20_3 corr20_5 cave20_5 open2x20 range dens40 t40; do
      dagger_paths+=("$work/dag$r/$name")
    done
    learn "$work/learned$r.pt" "$actor" "${all_paths[@]}" "${dagger_paths[@]}"
  done
  cp "$work/learned$rounds.pt" "$work/igbnet_learned.pt"
  cp "$work/learned$rounds.train.csv" "$work/igbnet_learned.train.csv"
  shipped+=(igbnet_learned)
fi
for m in "${shipped[@]}"; do
  cp "$work/$m.pt" "models/$m.pt"
  cp "$work/$m.train.csv" "models/$m.train.csv"
done
echo "models/{$(IFS=,; echo "${shipped[*]}")}.pt <- $work"
