#!/usr/bin/env bash
# The installed aia as a library (docs/extending.md): `cmake --install` into
# a temporary prefix, examples/cpp_policy built out of tree against it with
# find_package(aia), and its program scoring its policy with `eval`.
# Usage: tools/check_install.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: tools/check_install.sh BUILD_DIR}
src="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/aia_install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
cmake -S "$src/examples/cpp_policy" -B "$tmp/example" -G Ninja \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/configure.log" ||
  { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/example" > "$tmp/build.log" || { cat "$tmp/build.log"; exit 1; }
"$tmp/example/my_aia" policies | grep -q '^nearest_mean (distributed)'
# The plugins are found along the program's RUNPATH (aiaConfig.cmake).
readelf -d "$tmp/example/my_aia" | grep -q "RUNPATH.*$tmp/prefix/lib/aia" ||
  { echo "my_aia's RUNPATH lacks $tmp/prefix/lib/aia"; exit 1; }
"$tmp/example/my_aia" eval --sizes 3x3 --seeds 2 --policies nearest_mean,greedy \
  --out "$tmp/eval" --quiet > "$tmp/eval.log"
grep -q '^3x3,nearest_mean,2,' "$tmp/eval/summary.csv"
grep -q '^3x3,greedy,2,' "$tmp/eval/summary.csv"
# my_aia runs igbnet with the installed plugin and model (aia_installed_dirs.cc
# compiled into it), not the build tree's, still there, nor the source tree's.
(cd "$tmp" && LD_DEBUG=files LD_DEBUG_OUTPUT="$tmp/ld_my" "$tmp/example/my_aia" \
  run "$src/scenarios/default.yaml" --policy igbnet --max-steps 2 \
  --out "$tmp/my_run" --quiet > /dev/null)
loaded=$(cat "$tmp"/ld_my.* | grep -o 'file=[^ ]*libaia_torch.so' | sort -u)
[ "$(realpath "${loaded#file=}")" = "$(realpath "$tmp/prefix/lib/aia/libaia_torch.so")" ] ||
  { echo "my_aia loaded: $loaded"; exit 1; }
grep -q "model: $(realpath "$tmp/prefix")/share/aia/models/igbnet.pt" \
  "$tmp/my_run/effective.yaml" ||
  { echo "my_aia's model:"; grep model "$tmp/my_run/effective.yaml"; exit 1; }
# The installed Python package imports and steps a mission, with its own
# plugin and model (the build tree, still there, is not used), also when run
# from the source tree (whose models/igbnet.pt is there).
site=$(ls -d "$tmp"/prefix/lib/python3*/dist-packages 2>/dev/null | head -1)
if [ -n "$site" ]; then
  (cd "$src" && PYTHONPATH="$site" /usr/bin/python3 -c "
import os, aia
from aia import _aia
prefix = os.path.realpath('$tmp/prefix')
assert aia.__file__.startswith('$site'), aia.__file__
lib, data = _aia._installed_dirs()
assert os.path.realpath(lib) == prefix + '/lib/aia', lib
assert os.path.realpath(data) == prefix + '/share/aia', data
model = os.path.realpath(_aia._default_model_path())
assert model == prefix + '/share/aia/models/igbnet.pt', model
m = aia.Mission('$src/scenarios/default.yaml', overrides={'robots.count': 2, 'targets.count': 1})
m.step(aia.builtin_policy('greedy').decide(m))
m.step(aia.builtin_policy('igbnet').decide(m))
assert m.steps == 2
maps = [l.split()[-1] for l in open('/proc/self/maps') if 'libaia_torch' in l]
assert maps and all(os.path.realpath(p) == prefix + '/lib/aia/libaia_torch.so'
                    for p in maps), maps")
fi
# The installed CLI likewise, run from the source tree: its own plugin
# (LD_DEBUG=files names each file the loader opens) and its own model.
(cd "$src" && LD_DEBUG=files LD_DEBUG_OUTPUT="$tmp/ld" "$tmp/prefix/bin/aia" \
  run scenarios/default.yaml --policy igbnet --max-steps 2 --out "$tmp/run" \
  --quiet > /dev/null)
loaded=$(cat "$tmp"/ld.* | grep -o 'file=[^ ]*libaia_torch.so' | sort -u)
[ "$loaded" = "file=$tmp/prefix/bin/../lib/aia/libaia_torch.so" ] ||
  { echo "the installed aia loaded: $loaded"; exit 1; }
grep -q "model: $(realpath "$tmp/prefix")/share/aia/models/igbnet.pt" \
  "$tmp/run/effective.yaml" ||
  { echo "the installed aia's model:"; grep model "$tmp/run/effective.yaml"; exit 1; }
# What was installed: the program, the plugins, the models, the package.
for f in bin/aia lib/aia/libaia_torch.so lib/aia/libaia_media.so \
  share/aia/models/igbnet.pt lib/cmake/aia/aiaConfig.cmake \
  include/aia/commands/cli.h; do
  [ -e "$tmp/prefix/$f" ] || { echo "not installed: $f"; exit 1; }
done
echo "installed aia: an out-of-tree policy built and scored"
