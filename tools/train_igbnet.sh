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
# MODELS selects what is trained:
#   default    the two above;
#   learned    models/igbnet.pt (the default, where it starts) and
#              models/igbnet_learned.pt, the model meant for
#              policy.coordination=none (the network alone; four DAgger
#              rounds, then three with the loss among the valid moves in
#              worlds weighted to narrow perfect mazes, the last also with
#              the team starting in one corner, then an epoch with a
#              sharper reach channel, then one with it dimmed by the detour
#              from the robot on all that data and mazes of 1 m passages,
#              the neighbours channel then capped at 2 a pixel; about 2
#              hours 55 minutes more on 2 cores);
#   learned10  only WORK_DIR/igbnet_learned_10only.pt (not shipped): the
#              scalability check of the network alone, a model that never
#              saw more than 10 robots: the default's inputs on teams of 10
#              alone, then one epoch with the learned model's inputs (reach
#              over the workspace, L = 0.5 m, search points, trail; the loss
#              among the valid moves) on the same data and on teams of 10
#              in 8 and 11 m worlds (as many robots per square metre as 80
#              or 40 in 20 m); the datasets of other team sizes are not
#              made;
#   all        everything: the above, the ablation's four-channel model on
#              the randomized data and the five-channel 10-robot model
#              (the last three stay in WORK_DIR).
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
case $models in
  default | learned | learned10 | all) ;;
  *)
    echo "error: MODELS=$models: must be default, learned, learned10 or all" >&2
    exit 2
    ;;
esac
mkdir -p "$work"
# Jobs started with `&` record their pids; wait_all waits for them and
# fails (stopping the script) if any failed, which a bare `wait` would not.
pids=()
wait_all() {
  local pid rc=0
  for pid in "${pids[@]}"; do wait "$pid" || rc=$?; done
  pids=()
  return "$rc"
}

ds() {
  local out=$1
  shift
  "$aia" dataset --out "$work/$out" --quiet "$@"
}

# The paper's recipe: 1500 worlds of 10 robots and 10 targets, 20 x 20 m, 30
# boxes, 10 steps each (also the randomized data's open worlds).
ten=(d0)
all=(d0)
ds d0 --episodes 1500 & pids+=($!)
(
  # Small and large teams; every seed range is disjoint from aia eval's
  # (0.., selection 5000.., the generalization suite's 931000..) and from
  # each other. Teams of other sizes than 10 are not made for learned10.
  if [[ $models != learned10 ]]; then
    ds small5 --size 5x5 --keep 20 --episodes 400 --first-seed 21200000 \
      --set "workspace.size=[30,30]" --set workspace.obstacles.random.count=68
    ds small3r --size 3x3 --keep 30 --episodes 300 --first-seed 21300000 \
      --set workspace.obstacles.generator.type=rooms --set "workspace.size=[20,20]"
    ds small3m --size 3x3 --keep 30 --episodes 300 --first-seed 21400000 \
      --set workspace.obstacles.generator.type=maze --set "workspace.size=[20,20]"
    ds small2 --size 2x2 --keep 30 --episodes 300 --first-seed 21500000
  fi
  ds comm --episodes 300 --first-seed 21600000 --set communication.mode=range \
    --set communication.range=4 --set communication.packet_loss_lambda=1
  ds sens15 --episodes 150 --first-seed 21700000 --set sensor.range=1.5
  ds sens3 --episodes 150 --first-seed 21800000 --set sensor.range=3
  ds clutter0 --episodes 100 --first-seed 21900000 \
    --set workspace.obstacles.random.count=0
  ds clutter60 --episodes 150 --first-seed 22000000 \
    --set workspace.obstacles.random.count=60
  if [[ $models != learned10 ]]; then
    ds t40 --size 40x40 --episodes 200 --first-seed 22100000 --max-steps 60
    ds t80 --size 80x80 --episodes 200 --first-seed 22200000 --max-steps 40
  fi
) & pids+=($!)
wait_all
# Generated structured worlds of 10 robots, and larger workspaces at the
# paper's box density (0.075 per square metre).
k=0
for g in maze rooms corridors cave; do
  for side in 20 30; do
    k=$((k + 1))
    ds "g_${g}_$side" --episodes 150 --first-seed $((20000000 + k * 100000)) \
      --set "workspace.obstacles.generator.type=$g" \
      --set "workspace.size=[$side,$side]" & pids+=($!)
    ten+=("g_${g}_$side")
    if ((k % 2 == 0)); then wait_all; fi
  done
done
ds dens30 --episodes 300 --first-seed 21000000 --set "workspace.size=[30,30]" \
  --set workspace.obstacles.random.count=68 & pids+=($!)
ds dens40 --episodes 200 --first-seed 21100000 --set "workspace.size=[40,40]" \
  --set workspace.obstacles.random.count=120 & pids+=($!)
wait_all
ten+=(dens30 dens40 comm sens15 sens3 clutter0 clutter60)
all=("${ten[@]}" small5 small3r small3m small2 t40 t80)
paths() { for d in "$@"; do printf '%s\n' "$work/$d"; done; }
mapfile -t ten_paths < <(paths "${ten[@]}")
mapfile -t all_paths < <(paths "${all[@]}")

shipped=()
if [[ $models != learned10 ]]; then
  # The default: the reach channel (--geodesic), centred frame, weak labels
  # masked, cosine 1e-3 -> 1e-5 over 3 epochs, two libtorch threads (about 30
  # minutes alone on 2 cores; the thread count is part of the recipe: a
  # reduction over two threads does not add in the same order as over one).
  "$aia" train --data "${all_paths[@]}" --geodesic --epochs 3 --threads 2 \
    --out "$work/igbnet.pt" --weak-weight 0 --lr 1e-3 --lr-min 1e-5 --resume --quiet
  shipped+=(igbnet)
fi
if [[ $models == default || $models == all ]]; then
  # The paper's configuration (four channels, its dataset alone), as before
  # (MODELS=learned leaves it: the learned model starts from the default).
  "$aia" train --data "$work/d0" --out "$work/igbnet_10x10.pt" --weak-weight 0 \
    --epochs 8 --lr 1e-3 --lr-min 1e-5 --resume --quiet
  shipped+=(igbnet_10x10)
fi
if [[ $models == all ]]; then
  # The ablation's four-channel model on the same data.
  "$aia" train --data "${all_paths[@]}" --epochs 3 --threads 2 \
    --out "$work/ablation_4ch.pt" --weak-weight 0 --lr 1e-3 --lr-min 1e-5 --resume --quiet
fi
if [[ $models == all || $models == learned10 ]]; then
  # The 10-robot model: the default's inputs and recipe on teams of 10 only.
  "$aia" train --data "${ten_paths[@]}" --geodesic --epochs 3 --threads 2 \
    --out "$work/igbnet_10only.pt" --weak-weight 0 --lr 1e-3 --lr-min 1e-5 --resume --quiet
fi

# The learned-coordination recipe (docs/learning.md, Learned coordination):
# a five-channel model's weights, its reach channel over the whole workspace
# toward each target's search points and a trail channel (the pixel the
# robot came from) added, one epoch on its data; then DAgger rounds: the
# model alone (policy.coordination=none) acts in kinds of world of its
# team sizes, the expert labels the states it visits, and the next model is
# trained on the data and every round so far. About 25 minutes a round.
#   alone DIR ACTOR NAME SEED STEPS ARGS...: DAgger data into $work/DIR/NAME,
# ACTOR alone acting (policy.coordination=none) and the expert labelling,
# 20 steps kept per episode of at most STEPS, seeds from SEED.
alone() {
  local dir=$1 actor=$2 name=$3 seed=$4 steps=$5
  shift 5
  ds "$dir/$name" --policy igbnet --model "$actor" \
    --set policy.coordination=none --keep 20 --max-steps "$steps" \
    --first-seed "$seed" "$@"
}
#   dagger_worlds DIR ACTOR BASE NARROW: one round's data, the actor alone
# acting, into $work/DIR/NAME; the names, in the order training reads them,
# into the array dagger_names. The 15 worlds of the shipped model's rounds 1
# to 3; NARROW "narrow" adds narrow perfect mazes (passages of 3 lattice
# points, no loops) of 10 and 4 robots and of 30 m (its round 4). Seeds from
# BASE.
dagger_worlds() {
  local dir=$1 actor=$2 base=$3 narrow=$4
  local gen=workspace.obstacles.generator g=workspace.obstacles.generator.type
  local nar=(--set $g=maze --set $gen.corridor=1.5 --set $gen.wall=0.15)
  dag() { alone "$dir" "$actor" "$@"; }  # dag NAME SEED STEPS ARGS...
  (
    dag maze30 $((base + 100000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=maze
    dag rooms30 $((base + 200000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=rooms
    dag corr30 $((base + 300000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=corridors
    dag cave30 $((base + 400000)) 200 --episodes 100 --set "workspace.size=[30,30]" --set $g=cave
    dag maze40 $((base + 500000)) 300 --episodes 50 --set "workspace.size=[40,40]" --set $g=maze
    dag open10 $((base + 600000)) 200 --episodes 100
    dag rooms40 $((base + 1500000)) 300 --episodes 50 --set "workspace.size=[40,40]" --set $g=rooms
    if [[ $narrow == narrow ]]; then
      dag narrow20 $((base + 1610000)) 300 --episodes 60 "${nar[@]}" --set $gen.loops=0 \
        --set workspace.obstacles.random.count=0
    fi
  ) & pids+=($!)
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
    if [[ $narrow == narrow ]]; then
      dag narrow20_4 $((base + 1830000)) 300 --episodes 100 --size 4x6 "${nar[@]}" \
        --set $gen.loops=0 --set workspace.obstacles.random.count=0
      dag narrow30 $((base + 1710000)) 400 --episodes 30 --set "workspace.size=[30,30]" \
        "${nar[@]}" --set $gen.loops=0.05 --set workspace.obstacles.random.count=0
    fi
  ) & pids+=($!)
  wait_all
  dagger_names=(maze30 rooms30 corr30 cave30 maze40 open10 rooms40 rooms20_3 \
    maze20_3 corr20_5 cave20_5 open2x20 range dens40 t40)
  if [[ $narrow == narrow ]]; then
    dagger_names=(maze30 rooms30 corr30 cave30 maze40 open10 rooms40 narrow20 rooms20_3 \
      maze20_3 corr20_5 cave20_5 open2x20 range dens40 t40 narrow20_4 narrow30)
  fi
}
#   learned PREFIX INIT SEED_BASE SEED_STRIDE DATA...
# writes $work/PREFIX0.pt .. PREFIX$ROUNDS.pt; round r's worlds start at
# SEED_BASE + r SEED_STRIDE.
learned() {
  local prefix=$1 init=$2 seed_base=$3 seed_stride=$4
  shift 4
  local data=("$@")
  "$aia" train --data "${data[@]}" --init "$init" --reach-world 1 \
    --search 1 --trail 1 --epochs 1 --lr 3e-4 --lr-min 1e-5 --weak-weight 0 \
    --threads 2 --out "$work/${prefix}0.pt" --resume --quiet
  local dagger_paths=() r rounds=${ROUNDS:-3}
  for ((r = 1; r <= rounds; r++)); do
    local actor="$work/$prefix$((r - 1)).pt" base=$((seed_base + r * seed_stride))
    local dir="dag$r"
    dagger_worlds "$dir" "$actor" "$base" ""
    local name
    for name in "${dagger_names[@]}"; do dagger_paths+=("$work/$dir/$name"); done
    "$aia" train --data "${data[@]}" "${dagger_paths[@]}" --init "$actor" --epochs 1 \
      --lr 3e-4 --lr-min 1e-5 --weak-weight 0 --threads 2 \
      --out "$work/$prefix$r.pt" --resume --quiet
  done
  cp "$work/$prefix$rounds.pt" "$work/$prefix.pt"
  cp "$work/$prefix$rounds.train.csv" "$work/$prefix.train.csv"
}
if [[ $models == all || $models == learned ]]; then
  learned learned "$work/igbnet.pt" 30000000 1000000 "${all_paths[@]}"
  # Round 4 (2026-12-05): the model of round 3 alone acts in the same kinds
  # of world and in narrow perfect mazes (where it shuttled: docs/learning.md,
  # Learned coordination); one epoch on the base data and this round's.
  dagger_worlds dag4 "$work/learned.pt" 36000000 narrow
  narrow_paths=()
  for name in "${dagger_names[@]}"; do narrow_paths+=("$work/dag4/$name"); done
  "$aia" train --data "${all_paths[@]}" "${narrow_paths[@]}" --init "$work/learned.pt" \
    --epochs 1 --lr 3e-4 --lr-min 1e-5 --weak-weight 0 --threads 2 \
    --out "$work/learned4.pt" --resume --quiet
fi
if [[ $models == all || $models == learned10 ]]; then
  # The network alone trained on teams of 10 (2026-12-05, docs/learning.md,
  # Learned coordination): the 10-robot model above with the learned model's
  # inputs, one epoch on its data and on teams of 10 in small worlds at the
  # paper's box density (8 m: 0.16 robots per square metre, 80 robots in 20
  # m are 0.2; 11 m: 0.08), where robots stand as close together as in a
  # large team. Without those worlds the same epoch gave 0.85 success at 80
  # x 80 (40 selection worlds), with them 0.925.
  ds dense8 --episodes 1000 --first-seed 23000000 --set "workspace.size=[8,8]" \
    --set workspace.obstacles.random.count=5 & pids+=($!)
  ds dense11 --episodes 1000 --first-seed 23100000 --set "workspace.size=[11,11]" \
    --set workspace.obstacles.random.count=9 & pids+=($!)
  wait_all
  "$aia" train --data "${ten_paths[@]}" "$work/dense8" "$work/dense11" \
    --init "$work/igbnet_10only.pt" --reach-world 1 --search 1 --trail 1 \
    --geodesic-length 0.5 --valid-moves 1 --epochs 1 --lr 3e-4 --lr-min 1e-5 \
    --weak-weight 0 --threads 2 --out "$work/igbnet_learned_10only.pt" --resume --quiet
fi
# Rounds 5 to 7, the masked rounds (2026-12-05: docs/notes/2026-12-05-narrow-
# mazes-and-10-robot-model.md, "Forty worlds"): from the model of round 4,
# each round the model before alone acts in 11 kinds of world (8 of them
# narrow or generated mazes and rooms of 3 to 10 robots; 40 to 150
# episodes, each capped at 60 s), the expert labels, and the next model is
# one epoch on the base data and every masked round so far, the loss among
# the valid moves. Round 7 adds perfect mazes with the team starting in the
# bottom-left corner (as in scenarios/long/). Round 8 (below) starts from
# round 7's model, and its model is the one shipped.
#   masked_worlds DIR ACTOR BASE CORNER: one round's data into $work/DIR.
masked_worlds() {
  local dir=$1 actor=$2 base=$3 corner=$4
  local gen=workspace.obstacles.generator g=workspace.obstacles.generator.type
  local nar=(--set $g=maze --set $gen.corridor=1.5 --set $gen.wall=0.15)
  local open=(--set workspace.obstacles.random.count=0)
  dag() {  # dag NAME SEED STEPS ARGS...: each episode capped at 60 s
    alone "$dir" "$actor" "$1" "$2" "$3" --max-seconds 60 "${@:4}"
  }
  (
    dag narrow20_4 $((base + 100000)) 300 --episodes 100 --size 4x6 "${nar[@]}" --set $gen.loops=0 "${open[@]}"
    dag maze30 $((base + 200000)) 200 --episodes 30 --set "workspace.size=[30,30]" --set $g=maze "${open[@]}"
    dag open10 $((base + 300000)) 200 --episodes 40
    dag rooms30 $((base + 400000)) 200 --episodes 30 --set "workspace.size=[30,30]" --set $g=rooms "${open[@]}"
    dag narrow30 $((base + 1000000)) 400 --episodes 30 --set "workspace.size=[30,30]" "${nar[@]}" --set $gen.loops=0.05 "${open[@]}"
  ) & pids+=($!)
  (
    dag narrow20 $((base + 500000)) 300 --episodes 40 "${nar[@]}" --set $gen.loops=0 "${open[@]}"
    dag maze20_3 $((base + 600000)) 200 --episodes 40 --size 3x3 --set $g=maze "${open[@]}"
    dag corr20_5 $((base + 700000)) 200 --episodes 30 --size 5x5 --set $g=corridors "${open[@]}"
    dag cave30 $((base + 800000)) 200 --episodes 30 --set "workspace.size=[30,30]" --set $g=cave "${open[@]}"
    dag narrow20_4b $((base + 900000)) 300 --episodes 150 --size 4x6 "${nar[@]}" --set $gen.loops=0 "${open[@]}"
    dag rooms20_3 $((base + 1100000)) 200 --episodes 40 --size 3x3 --set $g=rooms "${open[@]}"
  ) & pids+=($!)
  wait_all
  masked_names=(cave30 corr20_5 maze20_3 maze30 narrow20 narrow20_4 narrow20_4b narrow30 open10 rooms20_3 rooms30)
  if [[ $corner == corner ]]; then
    local per=("${open[@]}" --set $g=maze --set $gen.loops=0 --set $gen.corridor=1.5 --set $gen.wall=0.15)
    local c4='[[0.25,0.25],[0.75,0.25],[0.25,0.75],[1.25,0.25]]'
    dag corner24 $((base + 2100000)) 500 --episodes 40 --size 5x7 --set "workspace.size=[24,24]" "${per[@]}" \
      --set "robots.start=[[0.25,0.25],[0.75,0.25],[0.25,0.75],[1.25,0.25],[0.75,0.75]]"
    dag corner20n $((base + 2200000)) 400 --episodes 80 --size 4x6 "${per[@]}" --set "robots.start=$c4"
    dag corner30 $((base + 2300000)) 600 --episodes 30 --size 6x8 --set "workspace.size=[30,30]" "${per[@]}" \
      --set "robots.start=[[0.25,0.25],[0.75,0.25],[0.25,0.75],[1.25,0.25],[0.75,0.75],[0.25,1.25]]"
    masked_names+=(corner24 corner20n corner30)
  fi
}
if [[ $models == all || $models == learned ]]; then
  masked_paths=()
  actor="$work/learned4.pt"
  for r in 5 6 7; do
    corner=""
    ((r < 7)) || corner=corner
    # Round 5's seeds from 50 000 000, round 6's 54 000 000, round 7's 55 000 000.
    base=$((r == 5 ? 50000000 : 48000000 + r * 1000000))
    masked_worlds "mdag$r" "$actor" "$base" "$corner"
    for name in "${masked_names[@]}"; do masked_paths+=("$work/mdag$r/$name"); done
    "$aia" train --data "${all_paths[@]}" "${masked_paths[@]}" --init "$actor" --epochs 1 \
      --lr 3e-4 --lr-min 1e-5 --weak-weight 0 --valid-moves 1 --threads 2 \
      --out "$work/masked$r.pt" --resume --quiet
    actor="$work/masked$r.pt"
  done
  # Round 8: the same data, the reach channel sharper (L = 0.25 m: a pixel
  # one move nearer the way reads e^2 = 7.4 times the robot's own, against
  # 1.1 at 5 m), the weights of round 7 kept. (Until 2026-12-05 L = 0.5 m,
  # written to sharp8.pt: the new name keeps an old work folder from
  # resuming into it.)
  "$aia" train --data "${all_paths[@]}" "${masked_paths[@]}" --init "$work/masked7.pt" \
    --geodesic-length 0.25 --epochs 1 --lr 3e-4 --lr-min 1e-5 --weak-weight 0 \
    --valid-moves 1 --threads 2 --out "$work/sharp8q.pt" --resume --quiet
  # Round 9 (2026-12-06, docs/notes/2026-12-06-detour-and-1m-passages.md):
  # the reach channel as the robot sees it (dimmed by each pixel's detour
  # from the robot, D = 0.5 m: the far side of a thin wall goes dark), and
  # mazes of 1 m passages. The actor is round 8's weights read through the
  # dimmed channel, untrained (tools/igbnet.py set); it acts alone in 20 m
  # mazes of 1 m passages (4 and 8 robots) and 30 m ones with the team in a
  # corner (about 4 minutes), the expert labels; then one epoch from round
  # 8's weights with the dimmed channel on all the data (about 7 minutes).
  actor="$work/detour9a.pt"
  /usr/bin/python3 tools/igbnet.py set "$work/sharp8q.pt" "$actor" reach_detour=0.5 >/dev/null
  one=(--set workspace.obstacles.generator.type=maze --set workspace.obstacles.generator.corridor=1.0
    --set workspace.obstacles.generator.wall=0.15 --set workspace.obstacles.random.count=0)
  loops=workspace.obstacles.generator.loops
  one9() { alone ddag9 "$actor" "$1" "$2" 300 --max-seconds 60 "${@:3}"; }  # one9 NAME SEED ARGS...
  (
    one9 narrow1_20l 58200000 --episodes 60 --size 8x8 "${one[@]}" --set $loops=0.1
    one9 corner1_30 58300000 --episodes 30 --size 6x8 "${one[@]}" --set "workspace.size=[30,30]" \
      --set $loops=0 --set "robots.start=[[0.25,0.25],[0.75,0.25],[0.25,0.75],[1.25,0.25],[0.75,0.75],[0.25,1.25]]"
  ) & pids+=($!)
  (
    one9 narrow1_20 58100000 --episodes 100 --size 4x6 "${one[@]}" --set $loops=0
    one9 narrow1_20b 58400000 --episodes 100 --size 4x6 "${one[@]}" --set $loops=0.05
  ) & pids+=($!)
  wait_all
  "$aia" train --data "${all_paths[@]}" "${masked_paths[@]}" \
    "$work"/ddag9/{narrow1_20,narrow1_20l,narrow1_20b,corner1_30} --init "$work/sharp8q.pt" \
    --reach-detour 0.5 --epochs 1 --lr 3e-4 --lr-min 1e-5 --weak-weight 0 \
    --valid-moves 1 --threads 2 --out "$work/detour9n.pt" --resume --quiet
  # Last (2026-12-06, docs/learning.md, Learned coordination): round 9's
  # weights with the neighbours channel capped at 2 a pixel, so that the
  # neighbours beyond the window, folded onto its border, read as they do
  # in the training teams of at most 80 (--epochs 0: no training, a second).
  "$aia" train --data "${all_paths[@]}" --init "$work/detour9n.pt" --neighbour-cap 2 \
    --epochs 0 --out "$work/igbnet_learned.pt" --quiet
  cp "$work/detour9n.train.csv" "$work/igbnet_learned.train.csv"
  shipped+=(igbnet_learned)
fi
for m in ${shipped[@]+"${shipped[@]}"}; do
  cp "$work/$m.pt" "models/$m.pt"
  cp "$work/$m.train.csv" "models/$m.train.csv"
done
if ((${#shipped[@]} > 0)); then
  echo "models/{$(IFS=,; echo "${shipped[*]}")}.pt <- $work"
else
  echo "$work/igbnet_learned_10only.pt (not copied into models/)"
fi
