#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The installed package as a user meets it: install the build tree to a fresh
# prefix, then build the installed samples as an outside CMake project with only
# find_package(pcl_dacpo) (C and PCL samples; a C++-only project too), build the
# C sample with pkg-config alone, and run what was built.
#
#   check_install.sh BUILD_DIR WORK_DIR
set -u
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
[ $# -eq 2 ] || fail "usage: check_install.sh BUILD_DIR WORK_DIR"
build="$1"
work="$2/package"
prefix="$work/prefix"
rm -rf "$work" && mkdir -p "$work" || fail "cannot make $work"

cmake --install "$build" --prefix "$prefix" >"$work/install.log" 2>&1 ||
  fail "cmake --install failed: $(tail -5 "$work/install.log")"
doc="$prefix/share/doc/pcl_dacpo"
for f in "$doc/LICENSE" "$doc/samples/CMakeLists.txt" "$prefix/lib/pkgconfig/dacpo.pc" \
  "$prefix/include/dacpo/dacpo.h" "$prefix/include/pcl_dacpo/dacpo_normal_orientation.h"; do
  [ -f "$f" ] || fail "not installed: $f"
done

# 1. the installed samples, as an outside project
cmake -S "$doc/samples" -B "$work/samples" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >"$work/samples.cfg.log" 2>&1 ||
  fail "configuring the samples failed: $(grep -A5 'CMake Error' "$work/samples.cfg.log" | head -20)"
cmake --build "$work/samples" -j 2 >"$work/samples.build.log" 2>&1 ||
  fail "building the samples failed: $(grep -E 'error|undefined' "$work/samples.build.log" | head -10)"
"$work/samples/orient_minimal" >"$work/minimal.log" 2>&1 || fail "orient_minimal failed"
[ -x "$work/samples/orient_pcd" ] || fail "orient_pcd was not built"

# 2. the README snippet in a C++-only project (Debian's VTK config needs C: the
#    package enables it) linking only pcl_dacpo::pcl_dacpo, reading and writing
#    clouds with PCL io
app="$work/app"
mkdir -p "$app"
cp "$doc/samples/pcl/orient_pcd.cpp" "$app/" || fail "no orient_pcd.cpp sample"
cat >"$app/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.16)
project(my_app CXX)
find_package(pcl_dacpo REQUIRED)
add_executable(my_app orient_pcd.cpp)
target_link_libraries(my_app PRIVATE pcl_dacpo::pcl_dacpo)
CMAKE
cmake -S "$app" -B "$app/build" -DCMAKE_PREFIX_PATH="$prefix" >"$app/cfg.log" 2>&1 ||
  fail "C++-only app: configure failed: $(grep -A5 'CMake Error' "$app/cfg.log" | head -20)"
cmake --build "$app/build" >"$app/build.log" 2>&1 ||
  fail "C++-only app: build failed: $(grep -E 'error|undefined' "$app/build.log" | head -10)"

# 2b. relocatable: the installed tools and the outside app run from this
#     prefix with no LD_LIBRARY_PATH (RUNPATH $ORIGIN/../lib, not /usr/local/lib)
for lib in "$prefix"/lib/libdacpo.so.0 "$prefix"/lib/libpcl_dacpo.so.0 "$prefix/bin/pcl_dacpo_orient"; do
  [ -e "$lib" ] || continue
  readelf -d "$lib" | grep -q 'R.*PATH.*\$ORIGIN' || fail "$lib: no \$ORIGIN in its RUNPATH"
done
if [ -x "$prefix/bin/pcl_dacpo_orient" ]; then
  env -u LD_LIBRARY_PATH "$prefix/bin/dacpo_make_scene" "$work/box.pcd" -scene box -n 3000 \
    >"$work/tool.log" 2>&1 || fail "the installed dacpo_make_scene does not run"
  env -u LD_LIBRARY_PATH "$prefix/bin/pcl_dacpo_orient" "$work/box.pcd" "$work/box_o.pcd" -q \
    >>"$work/tool.log" 2>&1 || fail "the installed pcl_dacpo_orient does not run: $(tail -3 "$work/tool.log")"
  env -u LD_LIBRARY_PATH "$app/build/my_app" "$work/box.pcd" "$work/box_app.pcd" \
    >>"$work/tool.log" 2>&1 || fail "the outside app does not run: $(tail -3 "$work/tool.log")"
fi

# 3. the C core with pkg-config alone
PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --exists dacpo || fail "pkg-config does not find dacpo"
# shellcheck disable=SC2046
cc -std=c11 -o "$work/minimal_pc" "$doc/samples/c/orient_minimal.c" \
  $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs dacpo) ||
  fail "compiling with pkg-config flags failed"
"$work/minimal_pc" >"$work/minimal_pc.log" 2>&1 || fail "the pkg-config build does not run"
# 4. the Python package, when it was built: importable from the prefix alone
py=$(ls -d "$prefix"/lib/python3.*/*-packages 2>/dev/null | head -1)
py="${py:-$prefix/lib/python3/dist-packages}"
if [ -d "$py/pcl_dacpo" ]; then
  (cd "$work" && PYTHONPATH="$py" /usr/bin/python3 -c "
import pcl_dacpo, numpy as np
pts, gt = pcl_dacpo.make_scene('box', 3000)
n, r = pcl_dacpo.orient(pts, ipsr_enabled=False)
assert np.mean(np.einsum('ij,ij->i', n, gt) > 0) > 0.99, r
") >"$work/python.log" 2>&1 || fail "the installed Python package fails: $(tail -5 "$work/python.log")"
fi
echo "package: installed, samples built out of tree, C++-only app built, pkg-config works"
exit 0
