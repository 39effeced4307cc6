#!/usr/bin/env bash
# bench/scale.sh: clvr end to end on ever larger generated meshes (issue #15):
# per size the peak resident set, the resident footprint after preprocessing
# and their ratio, every preprocessing stage's time, the load rate of the
# .bin, the mean frame time and the total render time, or the error clvr
# refused the mesh with. Meshes are generated at bench time (clvr-gen) into
# a data folder and reused; they are never committed.
#
# Usage: bench/scale.sh [--build DIR] [--data DIR] [--out DIR] [--sizes "10M 100M ..."]
#                       [--tets "791M"] [--spp N] [--size WxH] [--partitions K] [--keep]
#                       [--element-boxes on|off|auto] [--max-alloc BYTES] [--quiet]
#   --build       build directory with clvr and clvr-gen (default: build)
#   --data        where the generated .bin files go (default: /tmp/clvr-scale); needs
#                 37 bytes per mixed element and 20 per tet element of disk
#   --out         report folder (default: bench/results); writes
#                 <date>-scale.md and <date>-scale.json
#   --sizes       mixed meshes (clvr-gen mixed), default "10M 100M 300M 500M"
#   --tets        tetrahedral meshes (clvr-gen cellvar), default "791M" (788M asks for a
#                 508^3 lattice, 786.6M tets); "" for none
#   --spp         samples per pixel (default 16), --size image size (default 512x512)
#   --partitions  passed to clvr (default 0: automatic)
#   --element-boxes  passed to clvr (default auto: off only where the mesh fits only
#                 without them)
#   --max-alloc   run clvr with CLVR_MAX_ALLOC_BYTES=BYTES (docs/large-meshes.md): a
#                 lower per-buffer limit than the device's, so that the arrays of
#                 instance clusters are cut into pieces as on a GPU with a small
#                 CL_DEVICE_MAX_MEM_ALLOC_SIZE (default: unset)
#   --quiet       pass -q to clvr: no progress and no warnings scan (a pass over
#                 every element per duplicate-search group: minutes at 500M on 2 cores)
#   --keep        keep the generated meshes (default: a mesh above 100M elements is
#                 deleted after its run, so that the next one has the disk)
# Sizes that do not fit the disk are skipped with a line saying so. Timings
# on a shared machine: the load average is recorded with every run.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build
DATA=/tmp/clvr-scale
OUT=$ROOT/bench/results
SIZES="10M 100M 300M 500M"
TETS="791M"   # the lattice of 509^3 cubes x 6 tets: the first at or above the Lander's 788M
SPP=16
IMG=512x512
PARTS=0
KEEP=0
EBOX=auto
QUIET=
MAXALLOC=
while [ $# -gt 0 ]; do
  case $1 in
    --build) BUILD=$(cd "$2" && pwd); shift 2 ;;
    --data) DATA=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --sizes) SIZES=$2; shift 2 ;;
    --tets) TETS=$2; shift 2 ;;
    --spp) SPP=$2; shift 2 ;;
    --size) IMG=$2; shift 2 ;;
    --partitions) PARTS=$2; shift 2 ;;
    --keep) KEEP=1; shift ;;
    --element-boxes) EBOX=$2; shift 2 ;;
    --quiet) QUIET=-q; shift ;;
    --max-alloc) MAXALLOC=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "scale.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
for exe in clvr clvr-gen; do
  [ -x "$BUILD/$exe" ] || { echo "scale.sh: $BUILD/$exe not found; build first" >&2; exit 2; }
done
mkdir -p "$DATA" "$OUT"
DATE=$(date -u +%Y-%m-%d)
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
git -C "$ROOT" diff --quiet 2>/dev/null || COMMIT="$COMMIT-dirty"
RUNS=$(mktemp -d)
trap 'rm -rf "$RUNS"' EXIT

# elements as a number: 10M -> 10000000
count() { python3 -c "import sys; s=sys.argv[1]; m={'k':10**3,'M':10**6,'G':10**9}; print(int(float(s[:-1])*m[s[-1]]) if s[-1] in m else int(s))" "$1"; }

run_one() { # KIND SIZE
  local kind=$1 size=$2 gen file n need avail
  case $kind in mixed) gen=mixed; file=$DATA/mixed-$size.bin ;; tets) gen=cellvar; file=$DATA/tets-$size.bin ;; esac
  n=$(count "$size")
  if [ ! -f "$file" ]; then
    local per=38; [ "$kind" = mixed ] || per=21   # bytes per element of the .bin, with slack
    need=$(( n * per / 1024 ))
    avail=$(df -Pk "$DATA" | awk 'NR==2{print $4}')
    if [ "$need" -gt "$avail" ]; then
      echo "scale.sh: $kind $size needs ~$((need / 1048576)) GB of disk in $DATA, $((avail / 1048576)) GB free: skipped" >&2
      printf '%s\t%s\t%s\tskipped: disk\n' "$kind" "$size" "$n" >> "$RUNS/list"
      return 0
    fi
    echo "scale.sh: generating $file" >&2
    local g0=$(date +%s.%N)
    if ! nice "$BUILD/clvr-gen" "$gen" "$file" --elements "$size" --quiet; then
      printf '%s\t%s\t%s\tskipped: clvr-gen failed\n' "$kind" "$size" "$n" >> "$RUNS/list"
      return 0
    fi
    echo "scale.sh: generated in $(python3 -c "import time,sys; print(round(time.time()-float(sys.argv[1]),1))" "$g0") s" >&2
  fi
  # Cold or warm page cache is part of the load rate: say which (a file
  # just generated is warm).
  local tag="$kind-$size" load rc=0
  load=$(cut -d' ' -f1 /proc/loadavg)
  echo "scale.sh: clvr $file (load average $load)" >&2
  local t0=$(date +%s.%N)
  env ${MAXALLOC:+CLVR_MAX_ALLOC_BYTES=$MAXALLOC} nice "$BUILD/clvr" "$file" $QUIET -o "$RUNS/$tag.png" --spp "$SPP" --size "$IMG" --partitions "$PARTS" \
    --element-boxes "$EBOX" --stats-json "$RUNS/$tag.json" > "$RUNS/$tag.out" 2> "$RUNS/$tag.err" || rc=$?
  local wall
  wall=$(python3 -c "import time,sys; print(round(time.time()-float(sys.argv[1]),2))" "$t0")
  printf '%s\t%s\t%s\trc=%s\t%s\t%s\t%s\n' "$kind" "$size" "$n" "$rc" "$wall" "$load" "$(stat -c %s "$file")" >> "$RUNS/list"
  [ "$rc" = 0 ] || tail -3 "$RUNS/$tag.err" >&2
  if [ "$KEEP" = 0 ] && [ "$n" -gt 100000000 ]; then rm -f "$file"; fi
}

for s in $SIZES; do run_one mixed "$s"; done
for s in $TETS; do run_one tets "$s"; done

SUFFIX=${MAXALLOC:+-maxalloc$MAXALLOC}
python3 - "$RUNS" "$OUT/$DATE-scale$SUFFIX" "$COMMIT" "$DATE" "$SPP" "$IMG" "$MAXALLOC" <<'EOF'
import json, os, sys
runs, base, commit, date, spp, img, maxalloc = sys.argv[1:8]
rows = []
for line in open(os.path.join(runs, "list")):
    f = line.rstrip("\n").split("\t")
    kind, size, n = f[0], f[1], int(f[2])
    row = {"kind": kind, "size": size, "elements": n}
    if f[3].startswith("skipped"):
        row["skipped"] = f[3]
        rows.append(row); continue
    row.update(exit=int(f[3][3:]), wall_s=float(f[4]), load_average=float(f[5]), file_bytes=int(f[6]))
    tag = f"{kind}-{size}"
    try:
        st = json.load(open(os.path.join(runs, tag + ".json")))
        row["stats"] = st
    except (OSError, ValueError):
        err = open(os.path.join(runs, tag + ".err")).read().strip().splitlines()
        row["error"] = [l for l in err if l.startswith("clvr:")][-1:] or err[-1:]
    rows.append(row)
json.dump({"benchmark": "scale", "commit": commit, "date": date, "spp": int(spp), "image": img,
           "max_alloc_bytes": int(maxalloc) if maxalloc else None, "runs": rows},
          open(base + ".json", "w"), indent=1)
with open(base + ".md", "w") as md:
    md.write(f"bench/scale.sh at clvr commit {commit} ({date}), {img} at {spp} spp, PoCL on the 2-core 24 GiB VM"
             + (f", CLVR_MAX_ALLOC_BYTES={maxalloc}" if maxalloc else "") + "\n\n")
    md.write("| mesh | elements | partitions | peak RSS GB | resident GB | peak/resident | element boxes GB | load s | load GB/s | "
             "preprocess s | frame s (mean) | render s | load avg |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    stages = []
    for r in rows:
        name = f"{r['kind']} {r['size']}"
        if "skipped" in r:
            md.write(f"| {name} | {r['elements']} | {r['skipped']} ||||||||||\n"); continue
        st = r.get("stats")
        if not st:
            md.write(f"| {name} | {r['elements']} | exit {r['exit']}: {' '.join(r.get('error', []))} ||||||||||\n"); continue
        t = st["time"]; b = st["bytes"]; rd = st.get("render", {})
        peak, res = b.get("peak_rss", 0), b.get("resident", 0)
        md.write(f"| {name} | {st['elements']} | {st.get('partitions', 0):.0f} | {peak/1e9:.2f} | {res/1e9:.2f} | "
                 f"{peak/res if res else 0:.2f} | {b.get('element_boxes', 0)/1e9:.2f} | {t['load_s']:.2f} | {r['file_bytes']/1e9/t['load_s'] if t['load_s'] else 0:.2f} | "
                 f"{t['preprocess_s']:.2f} | {rd.get('frame_s', 0):.2f} | {rd.get('wall_s', 0):.1f} | {r['load_average']} |\n")
        stages.append((name, st["elements"], {k[:-2]: v for k, v in t.items() if k.endswith("_s") and k not in ("load_s", "preprocess_s", "kernel_build_s")}))
    if stages:
        names = list(stages[0][2].keys())
        md.write("\n| stage (s) | " + " | ".join(s[0] for s in stages) + " |\n|---|" + "---:|" * len(stages) + "\n")
        for k in names:
            md.write(f"| {k} | " + " | ".join(f"{s[2].get(k, 0):.3f}" for s in stages) + " |\n")
    md.write("\nframe s: the renderer's mean device seconds per frame (stats render.frame_s); "
             "render s: wall time of all frames.\n")
print(open(base + ".md").read())
EOF
