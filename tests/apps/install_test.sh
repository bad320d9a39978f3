#!/usr/bin/env bash
# Installs Penumbra into a scratch prefix, builds examples/ against it as a standalone project
# through find_package(penumbra), and runs the result: proof that the install works for users.
#   install_test.sh <build dir> <source dir> <scratch dir>
# Honours $CMAKE (the cmake to run) and $CXX (the compiler for the example project).
set -euo pipefail

if [[ $# -ne 3 ]]; then
  echo "usage: $0 <build dir> <source dir> <scratch dir>" >&2
  exit 2
fi
build=$1
source=$2
scratch=$3
cmake=${CMAKE:-cmake}
prefix=$scratch/prefix
example_build=$scratch/example-build
output=$scratch/render_in_code.png

step() { echo "== install_test: $*"; }
die() {
  echo "install_test: FAILED: $*" >&2
  exit 1
}

# A fresh scratch dir, so a stale install or cache cannot make the test pass.
rm -rf "$scratch"
mkdir -p "$scratch"

step "installing $build into $prefix"
"$cmake" --install "$build" --prefix "$prefix" || die "cmake --install failed"
[[ -f $prefix/lib/cmake/penumbra/penumbraConfig.cmake || -f $prefix/lib64/cmake/penumbra/penumbraConfig.cmake ]] ||
  die "no penumbraConfig.cmake under $prefix/lib*/cmake/penumbra"

step "configuring $source/examples as a standalone project"
"$cmake" -S "$source/examples" -B "$example_build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON ||
  die "configuring the example failed: find_package(penumbra) does not work from the install"

# The package must come from the scratch install, not from a copy elsewhere on the system.
found=$(sed -n 's/^penumbra_DIR:PATH=//p' "$example_build/CMakeCache.txt")
[[ $found == "$prefix"/* ]] || die "find_package(penumbra) found '$found', not the install in $prefix"

step "building the example"
env -u MAKELEVEL -u MAKEFLAGS -u MFLAGS "$cmake" --build "$example_build" --parallel || die "building the example against the install failed"

if [[ ${SHARED:-0} == 1 ]]; then
  # A shared install: the example links libpenumbra_*.so, found through the install's RUNPATH or
  # here through LD_LIBRARY_PATH, and nothing of the static dependency list.
  libdir=$(dirname "$(ls "$prefix"/lib*/libpenumbra_core.so | head -1)")
  [[ -n $libdir ]] || die "no libpenumbra_core.so under $prefix/lib*"
  export LD_LIBRARY_PATH=$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  linked=$(ldd "$example_build/render_in_code")  # whole, so grep cannot cut the pipe short
  [[ $linked == *libpenumbra_flatland.so* ]] ||
    die "the example is not linked against the shared libpenumbra_flatland.so"
  ! grep -q "OpenEXR\|embree" "$example_build/CMakeFiles/render_in_code.dir/link.txt" ||
    die "linking the example against the shared library named a private dependency"
fi

step "running the example"
"$example_build/render_in_code" "$output" || die "the example program failed"
[[ -s $output ]] || die "the example program did not write $output"
"$example_build/render_3d_in_code" "${output%.*}_3d.pfm" || die "the 3D example program failed"

step "OK: find_package(penumbra) works; wrote $output"
