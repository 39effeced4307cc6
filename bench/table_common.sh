# bench/table_common.sh: what the table scripts (render-table5.sh,
# locate-table2.sh) share; sourced, not run.
#
# table_args "$@": reads [--build DIR] [--data DIR] [--small] [-- ARGS] into
#   BUILD (default ROOT/build), DATA (default /tmp/clvr-bench), SMALL (0/1) and
#   EXTRA (the ARGS); --help prints the calling script's header comment.
# table_build TARGET...: builds the targets in BUILD; a build that fails (say,
#   another module mid-edit) falls back to binaries already there; exits when
#   one is missing.
# table_generated KIND N NAME: prints the path of generated mesh NAME.bin:
#   the shared /tmp/clvr-data one when present (same generator, same sizes),
#   else DATA's, which clvr-gen KIND --elements N writes when missing.
# All expect ROOT (the repository) to be set.

table_args() {
  BUILD=$ROOT/build
  DATA=/tmp/clvr-bench
  SMALL=0
  EXTRA=()
  while [ $# -gt 0 ]; do
    case $1 in
      --build) BUILD=$(cd "$2" && pwd); shift 2 ;;
      --data) DATA=$2; shift 2 ;;
      --small) SMALL=1; shift ;;
      --) shift; EXTRA=("$@"); break ;;
      -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
      *) echo "$(basename "$0"): unknown argument '$1' (try --help)" >&2; exit 2 ;;
    esac
  done
}

table_build() {
  cmake --build "$BUILD" -j2 $(printf -- '--target %s ' "$@") >/dev/null 2>&1 ||
    echo "$(basename "$0"): warning: 'cmake --build $BUILD' failed; using the binaries already built" >&2
  local t
  for t in "$@"; do
    [ -x "$BUILD/$t" ] || { echo "$(basename "$0"): $BUILD/$t missing; build it first" >&2; exit 1; }
  done
}

table_generated() {
  local f=/tmp/clvr-data/$3.bin
  [ -f "$f" ] || f=$DATA/$3.bin
  [ -f "$f" ] || "$BUILD/clvr-gen" "$1" "$f" --elements "$2" --quiet
  echo "$f"
}
