#!/usr/bin/env bash
# Proves `cmake --install` (issue 17): into a temporary prefix it puts clvr,
# clvr-gen and clvr-convert in bin/, clvr.1 (made from clvr --help, so it names
# every option the help names) in share/man/man1, README and docs/ in
# share/doc/clvr; the installed clvr runs from there (--help, --version, and a
# tiny render where an OpenCL device exists), away from the source tree.
# The fallback page maker (tools/man_from_help.cmake, for machines without
# help2man) is checked the same way.
# Usage: test_install.sh BUILD_DIR SOURCE_DIR
set -u
# The device the renders run on (tests/test_device.h: CLVR_TEST_DEVICE, default pocl).
DEV=${CLVR_TEST_DEVICE:-pocl}
BUILD=$1
SRC=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAILED: $*" >&2; }

if ! cmake --install "$BUILD" --prefix "$tmp/p" >"$tmp/install.log" 2>&1; then
  bad "cmake --install failed: $(tail -5 "$tmp/install.log")"
  echo "test_install: $pass passed, $fail failed"
  exit 1
fi
P=$tmp/p
for f in bin/clvr bin/clvr-gen bin/clvr-convert; do
  [ -x "$P/$f" ] && ok || bad "$f missing or not executable"
done
for f in share/man/man1/clvr.1 share/doc/clvr/README.md share/doc/clvr/docs/bin-format.md \
  share/doc/clvr/docs/transfer-function.md share/doc/clvr/docs/troubleshooting.md share/doc/clvr/docs/viewer.md; do
  [ -s "$P/$f" ] && ok || bad "$f missing or empty"
done
# Every link of the installed README into docs/ (pages, images, examples)
# resolves there: docs/ is installed beside it as in the source tree.
links=$(grep -oE '\]\(docs/[^)#]*' "$P/share/doc/clvr/README.md" | sed 's/^](//' | sort -u)
[ -n "$links" ] && ok || bad "no docs/ links found in the installed README"
for l in $links; do
  [ -s "$P/share/doc/clvr/$l" ] && ok || bad "installed README links to $l, which is not installed"
done
man1=$P/share/man/man1/clvr.1
cd "$tmp" || exit 1
"$P/bin/clvr" --help >"$tmp/help" 2>&1 && ok || bad "installed clvr --help failed"
# A man page: the .TH header, and every option of --help (roff writes - as \-).
check_man() {
  grep -q '^\.TH CLVR "\?1' "$1" && ok || bad "$1 has no .TH CLVR 1 header"
  sed 's/\\-/-/g; s/\\f[BIRP]//g; s/\\e/\\/g' "$1" >"$tmp/man.txt"
  local missing
  missing=$(grep -o -- '--[a-z][a-z-]*' "$tmp/help" | sort -u | while read -r opt; do
    grep -qF -- "$opt" "$tmp/man.txt" || echo "$opt"
  done)
  [ -z "$missing" ] && ok || bad "options of --help missing from $1: $missing"
}
check_man "$man1"
cmake -DCLVR="$P/bin/clvr" -DOUT="$tmp/fallback.1" -DVERSION=0 -P "$SRC/tools/man_from_help.cmake" &&
  check_man "$tmp/fallback.1" || bad "tools/man_from_help.cmake failed"
"$P/bin/clvr" --version | grep -q "^clvr [0-9]" && ok || bad "installed clvr --version"
"$P/bin/clvr-convert" --help >/dev/null 2>&1 && ok || bad "installed clvr-convert --help"
if "$P/bin/clvr" --list-devices >/dev/null 2>&1; then
  "$P/bin/clvr" --device "$DEV" --size 8x8 --spp 1 --quiet -o "$tmp/i.png" && [ -s "$tmp/i.png" ] && ok ||
    bad "installed clvr does not render"
else
  echo "note: no OpenCL device; the installed clvr's render is not tried"
fi

# libclvr (issue 18): the library with its soname links, clvr.h, the
# pkg-config and CMake package files, the Python module and the example.
for f in lib/libclvr.so lib/libclvr.so.1 include/clvr.h lib/pkgconfig/clvr.pc lib/cmake/clvr/clvrConfig.cmake \
  lib/cmake/clvr/clvrConfigVersion.cmake lib/cmake/clvr/clvrTargets.cmake lib/python3/dist-packages/clvr/__init__.py \
  lib/python3/dist-packages/clvr/_config.py share/doc/clvr/examples/clvr_turntable.py; do
  [ -e "$P/$f" ] && ok || bad "$f missing"
done
objdump -p "$P/lib/libclvr.so.1" 2>/dev/null | grep -q 'SONAME *libclvr.so.1' && ok || bad "libclvr.so.1 has no soname libclvr.so.1"
# An ASan+UBSan build's library needs the sanitizer runtimes in its users.
san=()
grep -q '^CLVR_SANITIZE:BOOL=ON' "$BUILD/CMakeCache.txt" 2>/dev/null && san=(-fsanitize=address,undefined)
cat >"$tmp/use.c" <<'EOC'
#include <clvr.h>
#include <stdio.h>
int main(void)
{
    clvr_message msg;
    clvr_dataset *ds = NULL;
    float xyz[3] = {0, 0, 0};
    clvr_dataset_info info; /* API 1.1: a versioned struct */
    if (clvr_api_version() != CLVR_API_VERSION) return 1;
    if (clvr_dataset_create(1, xyz, CLVR_COPY, &ds, &msg) != CLVR_RESULT_OK) return 2;
    info.size = sizeof info;
    if (clvr_dataset_get_info(ds, &info, &msg) != CLVR_RESULT_OK || info.num_points != 1) return 4;
    if (clvr_dataset_add_cells(ds, "tetra", 0, NULL, CLVR_COPY, &msg) != CLVR_RESULT_OK) return 3;
    clvr_dataset_destroy(ds);
    printf("clvr %s API %u\n", clvr_version_string(), clvr_api_version());
    return 0;
}
EOC
# The API version of this source tree's clvr.h (1.2: 1002).
api_major=$(sed -n 's/^#define CLVR_API_VERSION_MAJOR \([0-9]*\)$/\1/p' "$SRC/host/api/clvr.h")
api_minor=$(sed -n 's/^#define CLVR_API_VERSION_MINOR \([0-9]*\)$/\1/p' "$SRC/host/api/clvr.h")
api=$((api_major * 1000 + api_minor))
# pkg-config: compile, link and run against the installed library only.
if PKG_CONFIG_PATH="$P/lib/pkgconfig" pkg-config --exact-version="$api_major.$api_minor.0" clvr; then
  ok
  # shellcheck disable=SC2046
  cc "${san[@]}" "$tmp/use.c" -o "$tmp/use_pc" $(PKG_CONFIG_PATH="$P/lib/pkgconfig" pkg-config --cflags --libs clvr) &&
    LD_LIBRARY_PATH="$P/lib" "$tmp/use_pc" | grep -q "^clvr .* API $api\$" && ok || bad "a program built with pkg-config clvr"
else
  bad "pkg-config does not find clvr $api_major.$api_minor.0 in $P/lib/pkgconfig"
fi
# CMake: find_package(clvr MAJOR.MINOR REQUIRED) and the clvr::clvr target.
mkdir -p "$tmp/cm"
cp "$tmp/use.c" "$tmp/cm/use.c"
cat >"$tmp/cm/CMakeLists.txt" <<EOC
cmake_minimum_required(VERSION 3.20)
project(use_clvr C)
find_package(clvr $api_major.$api_minor REQUIRED)
add_executable(use use.c)
target_compile_options(use PRIVATE ${san[*]})
target_link_options(use PRIVATE ${san[*]})
target_link_libraries(use PRIVATE clvr::clvr)
EOC
if cmake -S "$tmp/cm" -B "$tmp/cm/b" -DCMAKE_PREFIX_PATH="$P" >"$tmp/cm.log" 2>&1 &&
  cmake --build "$tmp/cm/b" >>"$tmp/cm.log" 2>&1 && "$tmp/cm/b/use" | grep -q "API $api\$"; then
  ok
else
  bad "find_package(clvr): $(grep -m3 -B2 -A3 "error" "$tmp/cm.log")"
fi
# The installed clvr runs on the installed libclvr (its RPATH, not
# LD_LIBRARY_PATH or the build tree), and on the MPI module when built with it.
real_p=$(realpath "$P")
loads() { # loads LIB: the real path the installed clvr loads LIB from
  local f
  f=$(env -u LD_LIBRARY_PATH ldd "$P/bin/clvr" | sed -n "s/^[[:space:]]*$1 => \([^ ]*\) .*/\1/p")
  [ -n "$f" ] && realpath "$f"
}
[ "$(loads "libclvr\.so\.$api_major")" = "$real_p/lib/libclvr.so.$api_major.$api_minor.0" ] && ok ||
  bad "installed clvr does not load $P/lib/libclvr.so.$api_major: $(ldd "$P/bin/clvr" | grep clvr)"
if grep -q '^CLVR_MPI:BOOL=ON' "$BUILD/CMakeCache.txt" 2>/dev/null && [ -e "$BUILD/libclvr_mpi.so" ]; then
  [ -e "$P/lib/libclvr_mpi.so.$api_major" ] && [ -e "$P/include/clvr_mpi.h" ] && ok || bad "libclvr_mpi.so or clvr_mpi.h not installed"
  [ "$(loads "libclvr_mpi\.so\.$api_major")" = "$real_p/lib/libclvr_mpi.so.$api_major.$api_minor.0" ] && ok ||
    bad "installed clvr does not load $P/lib/libclvr_mpi.so.$api_major"
  # pkg-config clvr_mpi: a program calling the module, built with its flags
  # alone, runs outside mpirun (clvr_mpi_launched() is 0 there).
  cat >"$tmp/use_mpi.c" <<'EOC'
#include <clvr_mpi.h>
#include <stdio.h>
int main(void)
{
    printf("launched %d\n", clvr_mpi_launched());
    return 0;
}
EOC
  if PKG_CONFIG_PATH="$P/lib/pkgconfig" pkg-config --exact-version="$api_major.$api_minor.0" clvr_mpi; then
    ok
    # shellcheck disable=SC2046
    cc "${san[@]}" "$tmp/use_mpi.c" -o "$tmp/use_mpi" $(PKG_CONFIG_PATH="$P/lib/pkgconfig" pkg-config --cflags --libs clvr_mpi) &&
      env -u OMPI_COMM_WORLD_SIZE -u PMI_SIZE -u PMIX_RANK LD_LIBRARY_PATH="$P/lib" "$tmp/use_mpi" | grep -q "^launched 0$" &&
      ok || bad "a program built with pkg-config clvr_mpi"
  else
    bad "pkg-config does not find clvr_mpi $api_major.$api_minor.0 in $P/lib/pkgconfig"
  fi
fi
# The program (all of host/app but the GLFW viewer) builds from the
# installed headers and library alone, no source tree include paths but its
# own folder: it uses clvr.h (and clvr_mpi.h) only. Then it runs.
app=$SRC/host/app
mpi_flags=()
[ -e "$P/include/clvr_mpi.h" ] && mpi_flags=(-DCLVR_HAVE_MPI -lclvr_mpi)
if cc -std=c11 -Wall -Werror -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE "${san[@]}" -I"$P/include" -I"$app" \
  "$app/main.c" "$app/cli.c" "$app/series.c" "$app/info.c" "$app/stats.c" "$app/message.c" -o "$tmp/clvr_app" \
  -L"$P/lib" -Wl,-rpath,"$P/lib" -lclvr "${mpi_flags[@]}" -lm 2>"$tmp/app.log"; then
  ok
  "$tmp/clvr_app" --version | grep -q "^clvr [0-9]" && ok || bad "the program built on the installed library: --version"
  if "$P/bin/clvr" --list-devices >/dev/null 2>&1; then
    "$tmp/clvr_app" --device "$DEV" --size 8x8 --spp 1 --quiet -o "$tmp/j.png" && [ -s "$tmp/j.png" ] && ok ||
      bad "the program built on the installed library does not render"
  fi
else
  bad "host/app does not build against the installed clvr.h and libclvr alone: $(head -5 "$tmp/app.log")"
fi
# The installed Python module finds the installed library (not the build
# tree's: CLVR_LIBRARY unset, run from $tmp). Not for sanitizer builds.
if [ ${#san[@]} -eq 0 ] && /usr/bin/python3 -c "import numpy" 2>/dev/null; then
  out=$(env -u CLVR_LIBRARY PYTHONPATH="$P/lib/python3/dist-packages" /usr/bin/python3 -c '
import clvr, os, sys
print(os.path.realpath(clvr._lib._name))
' 2>&1)
  case $out in
    "$(realpath "$P")"/lib/libclvr.so*) ok ;;
    *) bad "installed module loads $out, not $P/lib/libclvr.so.1" ;;
  esac
  if "$P/bin/clvr" --list-devices >/dev/null 2>&1; then
    PYTHONPATH="$P/lib/python3/dist-packages" CLVR_SHARED_DATA="$SRC/tests/data" CLVR_BUILD_DIR="$BUILD" \
      /usr/bin/python3 "$SRC/tests/test_python.py" --quick && ok || bad "the installed Python module (test_python.py --quick)"
    if /usr/bin/python3 -c "import meshio" 2>/dev/null; then
      PYTHONPATH="$P/lib/python3/dist-packages" /usr/bin/python3 "$P/share/doc/clvr/examples/clvr_turntable.py" \
        "$SRC/tests/data/vtk/fire_ug.vtu" -o "$tmp/turn" --frames 8 --spp 1 --size 32x24 2>"$tmp/turn.log" &&
        [ "$(ls "$tmp"/turn.00*.png | wc -l)" -eq 8 ] && ok || bad "the installed turntable example: $(tail -3 "$tmp/turn.log")"
    fi
  fi
fi

echo "test_install: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
