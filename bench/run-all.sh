#!/usr/bin/env bash
# bench/run-all.sh: every benchmark program in the build directory on every OpenCL
# device, one Markdown report and one JSON file per device in bench/results/.
#
# Usage: bench/run-all.sh [--build DIR] [--out DIR] [--device SPEC]... [--only NAME]...
#                         [--timeout SECONDS] [-- ARGS passed to every benchmark]
#   --build    build directory holding clvr and bench_* (default: build)
#   --out      where reports go (default: bench/results)
#   --device   run only on this device (P:D or any clvr --device SPEC); repeatable.
#              Default: every device `clvr --list-devices` (or `clinfo -l`) shows.
#   --only     run only this benchmark (bench_locate or locate); repeatable
#   --timeout  per benchmark and device (default 3600 s)
#
# The benchmark contract (see bench/README.md): a program named bench_* that accepts
# `--device SPEC --json FILE`, prints its device line and a Markdown table to stdout,
# writes one JSON object to FILE and exits 0 on success.
#
# Output: OUT/<YYYY-MM-DD>-<device-slug>.md and .json, headed by device, platform,
# driver, clvr commit (git rev-parse --short HEAD, "-dirty" with local changes) and
# date. Exit status: 0 when every benchmark passed (or none exists), 1 otherwise.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build
OUT=$ROOT/bench/results
TIMEOUT=3600
DEVICES=()
ONLY=()
EXTRA=()
while [ $# -gt 0 ]; do
  case $1 in
    --build) BUILD=$(cd "$2" && pwd); shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --device) DEVICES+=("$2"); shift 2 ;;
    --only) ONLY+=("bench_${2#bench_}"); shift 2 ;;
    --timeout) TIMEOUT=$2; shift 2 ;;
    --) shift; EXTRA=("$@"); break ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "run-all.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done

# Benchmarks: executables named bench_* directly in the build directory.
BENCHES=()
for f in "$BUILD"/bench_*; do
  if [ ! -f "$f" ] || [ ! -x "$f" ]; then continue; fi
  name=$(basename "$f")
  if [ ${#ONLY[@]} -gt 0 ] && [[ ! " ${ONLY[*]} " == *" $name "* ]]; then continue; fi
  BENCHES+=("$name")
done
if [ ${#BENCHES[@]} -eq 0 ]; then
  echo "run-all.sh: no benchmarks found (no executable $BUILD/bench_*${ONLY[*]:+ matching ${ONLY[*]}}); build them with: cmake --build ${BUILD#"$ROOT"/}"
  exit 0
fi

# Devices as "P:D<TAB>name<TAB>platform<TAB>driver", from clvr when it lists them,
# otherwise from clinfo.
list_devices() {
  local out
  if [ -x "$BUILD/clvr" ] && out=$("$BUILD/clvr" --list-devices 2>/dev/null) &&
     grep -q '^  device [0-9]*:[0-9]*  ' <<<"$out"; then
    # platform 0: NAME (...)
    #   device 0:0  NAME
    #       type CPU, vendor V, OpenCL 3.0 ..., driver 3.1+debian
    awk '
      /^platform [0-9]+: / { p = $0; sub(/^platform [0-9]+: /, "", p); sub(/ \(.*$/, "", p) }
      /^  device [0-9]+:[0-9]+  / { if (id != "") print id "\t" name "\t" dp "\t" drv
                                    id = $2; dp = p; name = $0; sub(/^  device [0-9]+:[0-9]+  /, "", name); drv = "" }
      /^      .*driver / { d = $0; sub(/.*driver /, "", d); sub(/[ ,].*$/, "", d); drv = d }
      END { if (id != "") print id "\t" name "\t" dp "\t" drv }' <<<"$out"
  elif command -v clinfo >/dev/null 2>&1; then
    clinfo -l 2>/dev/null | awk '
      /^Platform #[0-9]+: / { pi = $2; sub(/#/, "", pi); sub(/:$/, "", pi); p = $0; sub(/^Platform #[0-9]+: /, "", p) }
      /Device #[0-9]+: / { di = $0; sub(/.*Device #/, "", di); sub(/:.*/, "", di)
                           n = $0; sub(/.*Device #[0-9]+: /, "", n); print pi ":" di "\t" n "\t" p "\t" }' |
    while IFS=$'\t' read -r id name plat _; do
      drv=$(clinfo -d "$id" --prop CL_DRIVER_VERSION 2>/dev/null | awk '{ $1 = $2 = ""; sub(/^ +/, ""); print; exit }')
      printf '%s\t%s\t%s\t%s\n' "$id" "$name" "$plat" "$drv"
    done
  fi
}

mapfile -t ALL < <(list_devices)
if [ ${#DEVICES[@]} -gt 0 ]; then
  # Keep the listing's name and driver for devices given as P:D; others as given.
  SEL=()
  for spec in "${DEVICES[@]}"; do
    line=$(printf '%s\n' "${ALL[@]}" | awk -F'\t' -v s="$spec" '$1 == s' | head -n 1)
    [ -n "$line" ] || printf -v line '%s\t%s\t\t' "$spec" "$spec"
    SEL+=("$line")
  done
  ALL=("${SEL[@]}")
fi
if [ ${#ALL[@]} -eq 0 ]; then
  echo "run-all.sh: no OpenCL devices found (neither $BUILD/clvr --list-devices nor clinfo -l lists one)" >&2
  exit 1
fi

COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ "$COMMIT" != unknown ] && ! git -C "$ROOT" diff --quiet HEAD 2>/dev/null; then
  COMMIT=$COMMIT-dirty
fi
DATE=$(date -u +%Y-%m-%d)
STAMP=$(date -u +%Y-%m-%dT%H:%M:%SZ)
HOST_CPU=$("$ROOT/bench/host-cpu.sh")
mkdir -p "$OUT"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

failed=0
for entry in "${ALL[@]}"; do
  IFS=$'\t' read -r id name plat drv <<<"$entry"
  slug=$(printf '%s' "$name" | tr '[:upper:]' '[:lower:]' | tr -cs 'a-z0-9' '-' | sed 's/^-*//; s/-*$//' | cut -c1-60)
  base=$OUT/$DATE-${slug:-device}
  md=$WORK/report.md
  {
    echo "# clvr benchmarks on $name"
    echo
    echo "| | |"
    echo "|---|---|"
    echo "| device | \`$id\` $name |"
    echo "| platform | $plat |"
    echo "| driver | ${drv:-unknown} |"
    echo "| clvr commit | $COMMIT |"
    echo "| date | $STAMP |"
    echo "| host | $(hostname), ${HOST_CPU:-unknown CPU}, $(nproc) cores |"
    [ ${#EXTRA[@]} -eq 0 ] || echo "| arguments | \`${EXTRA[*]}\` |"
  } >"$md"
  : >"$WORK/runs.tsv"
  for b in "${BENCHES[@]}"; do
    echo "run-all.sh: $b on $id $name"
    log=$WORK/$b.out
    json=$WORK/$b.json
    rm -f "$json"
    start=$(date +%s.%N)
    rc=0
    timeout "$TIMEOUT" "$BUILD/$b" --device "$id" --json "$json" "${EXTRA[@]}" >"$log" 2>&1 || rc=$?
    secs=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    [ $rc -eq 0 ] || failed=1
    {
      echo
      echo "## $b"
      echo
      if [ $rc -ne 0 ]; then
        echo "**failed**: exit $rc$([ $rc -eq 124 ] && echo " (timed out after $TIMEOUT s)") after $secs s; output:"
        echo
        echo '```'
        tail -n 40 "$log"
        echo '```'
      else
        cat "$log"
        echo
        echo "_${secs} s_"
      fi
    } >>"$md"
    printf '%s\t%s\t%s\t%s\t%s\n' "$b" "$rc" "$secs" "$json" "$log" >>"$WORK/runs.tsv"
    sed 's/^/    /' "$log"
  done
  python3 "$ROOT/bench/collect_json.py" "$WORK/runs.tsv" "$WORK/report.json" \
    device="$name" device_spec="$id" platform="$plat" driver="$drv" commit="$COMMIT" \
    date="$STAMP" host="$(hostname)" cpu="$HOST_CPU" arguments="${EXTRA[*]}"
  # Complete files only: written beside the target, then renamed.
  cp "$md" "$base.md.tmp" && mv "$base.md.tmp" "$base.md"
  cp "$WORK/report.json" "$base.json.tmp" && mv "$base.json.tmp" "$base.json"
  echo "run-all.sh: wrote ${base#"$ROOT"/}.md and .json"
done
exit $failed
