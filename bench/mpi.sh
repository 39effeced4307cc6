#!/usr/bin/env bash
# bench/mpi.sh: MPI mode against one process on the same two cores (issue 16):
# 1 rank x 2 PoCL threads against 2 ranks x 1 PoCL thread each, same mesh,
# image and options. Per configuration: the mean frame time (render wall time
# over frames, rank 0's clock, light grid included), the share of it each rank
# spent inside MPI calls (communication and waiting for the other rank), the
# relative RMSE against a long single-process reference, the time to the
# 1-process image's quality (frame time x frames x (RMSE / RMSE of 1 process)^2:
# the 1/n law of independent frames), the peak resident memory per rank and the
# resident memory once the rank holds its share only. Parallel efficiency is
# the 1-process time over the 2-rank time, per frame and to equal quality.
#
# Usage: bench/mpi.sh [--build DIR] [--out DIR] [--mesh FILE] [--size WxH] [--spp N]
#                     [--ref-spp N] [--repeat K]
#   --mesh     default: the built-in scene
#   --size     default 128x128; --spp default 32; --ref-spp (reference) default 256
#   --repeat   runs per configuration, interleaved (default 2; the fastest counts)
#   --out      report folder (default bench/results/mpi): <date>-mpi.md and .json
# PoCL threads: this PoCL (3.1) honours POCL_MAX_PTHREAD_COUNT; newer ones read
# POCL_CPU_MAX_CU_COUNT. Both are set. The load average is recorded per run.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build
OUT=$ROOT/bench/results/mpi
MESH=""
SIZE=128x128
SPP=32
REF_SPP=256
REPEAT=2
while [ $# -gt 0 ]; do
  case $1 in
    --build) BUILD=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --mesh) MESH=$2; shift 2 ;;
    --size) SIZE=$2; shift 2 ;;
    --spp) SPP=$2; shift 2 ;;
    --ref-spp) REF_SPP=$2; shift 2 ;;
    --repeat) REPEAT=$2; shift 2 ;;
    *) echo "bench/mpi.sh: unknown option $1 (see the header for usage)" >&2; exit 2 ;;
  esac
done
CLVR=$BUILD/clvr
[ -x "$CLVR" ] || { echo "bench/mpi.sh: no $CLVR; build first" >&2; exit 1; }
command -v mpirun >/dev/null || { echo "bench/mpi.sh: no mpirun (apt-get install openmpi-bin)" >&2; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
TMP=$(mktemp -d /tmp/clvr-bench-mpi.XXXXXX)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
ARGS=(--size "$SIZE" --quiet)
[ -n "$MESH" ] && ARGS+=("$MESH")

load() { cut -d' ' -f1 /proc/loadavg; }

echo "reference: 1 process, $REF_SPP spp" >&2
POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 "$CLVR" "${ARGS[@]}" --spp "$REF_SPP" --seed 99 -o "$TMP/ref.pfm"

runs=()
for k in $(seq 1 "$REPEAT"); do
  for cfg in 1x2 2x1; do
    ranks=${cfg%x*}
    threads=${cfg#*x}
    l0=$(load)
    # Open MPI binds each rank to one core when there are 2 ranks or fewer:
    # a rank with 2 PoCL threads must be left unbound, or both threads share a core.
    bind=()
    [ "$threads" -gt 1 ] && bind=(--bind-to none)
    POCL_MAX_PTHREAD_COUNT=$threads POCL_CPU_MAX_CU_COUNT=$threads \
      mpirun --oversubscribe "${bind[@]}" -n "$ranks" "$CLVR" "${ARGS[@]}" --spp "$SPP" --seed $((k + 10)) \
      -o "$TMP/$cfg-$k.pfm" --stats-json "$TMP/$cfg-$k.json"
    echo "$cfg run $k done (load $l0 -> $(load))" >&2
    runs+=("$cfg $k $l0 $(load)")
  done
done
printf '%s\n' "${runs[@]}" >"$TMP/runs.txt"
# The stricter baseline: one plain process (no mpirun, no compositing) with 2
# PoCL threads, the fastest of REPEAT runs.
for k in $(seq 1 "$REPEAT"); do
  POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 \
    "$CLVR" "${ARGS[@]}" --spp "$SPP" --seed $((k + 10)) -o "$TMP/plain-$k.pfm" --stats-json "$TMP/plain-$k.json"
done
# The fixed overhead per rank (PoCL, its compiled kernels, MPI): the resident
# memory of the same configurations on a 2k-element mesh.
for cfg in 1x2 2x1; do
  ranks=${cfg%x*}
  threads=${cfg#*x}
  POCL_MAX_PTHREAD_COUNT=$threads POCL_CPU_MAX_CU_COUNT=$threads \
    mpirun --oversubscribe -n "$ranks" "$CLVR" --size "$SIZE" --quiet --spp 1 "$ROOT/tests/data/vtk/notch_stress.vtk" \
    -o "$TMP/fixed-$cfg.pfm" --stats-json "$TMP/fixed-$cfg.json"
done

DATE=$(date -u +%Y-%m-%d)
python3 - "$TMP" "$OUT/$DATE-mpi" "$SIZE" "$SPP" "$REF_SPP" "${MESH:-built-in scene}" <<'PY'
import json, math, os, struct, sys
tmp, base, size, spp, ref_spp, mesh = sys.argv[1:]
spp = int(spp)

def pfm(p):
    with open(p, "rb") as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); sc = float(f.readline())
        n = w * h * 3
        return struct.unpack(("<" if sc < 0 else ">") + "%df" % n, f.read(4 * n))

ref = pfm(os.path.join(tmp, "ref.pfm"))
rms_ref = math.sqrt(sum(v * v for v in ref) / len(ref))
runs = [l.split() for l in open(os.path.join(tmp, "runs.txt"))]
best = {}
for cfg, k, l0, l1 in runs:
    j = json.load(open(os.path.join(tmp, f"{cfg}-{k}.json")))
    img = pfm(os.path.join(tmp, f"{cfg}-{k}.pfm"))
    rmse = math.sqrt(sum((a - b) ** 2 for a, b in zip(img, ref)) / len(ref)) / rms_ref
    pr = j["per_rank"]
    row = {"config": cfg, "run": int(k), "load_before": float(l0), "load_after": float(l1), "frame_s": j["frame_s"],
           "frames": j["frames"], "rel_rmse": rmse, "comm_share": [r["comm_share"] for r in pr],
           "peak_rss_mib": [r["bytes_peak_rss"] / 2**20 for r in pr],
           "resident_mib": [r["bytes_resident"] / 2**20 for r in pr],
           "elements": [r["elements"] for r in pr], "owned": [r["owned_elements"] for r in pr]}
    if cfg not in best or row["frame_s"] < best[cfg]["frame_s"]:
        best[cfg] = row
one, two = best["1x2"], best["2x1"]
plain = None
for k in range(1, len(runs) // 2 + 1):
    pj = os.path.join(tmp, f"plain-{k}.json")
    if not os.path.exists(pj):
        continue
    j = json.load(open(pj))
    img = pfm(os.path.join(tmp, f"plain-{k}.pfm"))
    rmse = math.sqrt(sum((a - b) ** 2 for a, b in zip(img, ref)) / len(ref)) / rms_ref
    # Wall seconds a frame, as the MPI rows' frame_s (rank 0's wall clock);
    # render.frame_s is device seconds, which leave out the host's share.
    r = {"config": "plain 1 process x 2 threads", "frame_s": j["render"]["wall_s"] / j["render"]["frames"],
         "frames": j["render"]["frames"],
         "rel_rmse": rmse, "peak_rss_mib": j["bytes"]["peak_rss"] / 2**20, "resident_mib": j["bytes"]["resident"] / 2**20}
    if plain is None or r["frame_s"] < plain["frame_s"]:
        plain = r
for r in (one, two):
    # Time to the 1-process image's RMSE at `spp` frames (1/n law).
    r["time_to_quality_s"] = r["frame_s"] * r["frames"] * (r["rel_rmse"] / one["rel_rmse"]) ** 2
eff_frame = one["frame_s"] / two["frame_s"]
plain["time_to_quality_s"] = plain["frame_s"] * plain["frames"] * (plain["rel_rmse"] / one["rel_rmse"]) ** 2
eff_plain_frame = plain["frame_s"] / two["frame_s"]
eff_plain_quality = plain["time_to_quality_s"] / two["time_to_quality_s"]
eff_quality = one["time_to_quality_s"] / two["time_to_quality_s"]
fixed = {c: [r["bytes_resident"] / 2**20 for r in json.load(open(os.path.join(tmp, f"fixed-{c}.json")))["per_rank"]]
         for c in ("1x2", "2x1")}
# Memory per rank against 1/N of one process's, the fixed overhead apart:
# (resident - fixed) / ((resident of 1 process - its fixed) / N).
var_one = one["resident_mib"][0] - fixed["1x2"][0]
var_ratio = [(m - f) / (var_one / len(two["resident_mib"])) for m, f in zip(two["resident_mib"], fixed["2x1"])]
fixed_peak = {c: [r["bytes_peak_rss"] / 2**20 for r in json.load(open(os.path.join(tmp, f"fixed-{c}.json")))["per_rank"]]
              for c in ("1x2", "2x1")}
# Peak per rank, its fixed part (the peak on the 2k-element mesh) apart, over
# 1/N of the plain process's peak less the 1-rank fixed peak: the stricter
# reading of "memory per rank".
peak_ratio = [(m - f) / ((plain["peak_rss_mib"] - fixed_peak["1x2"][0]) / len(two["peak_rss_mib"]))
              for m, f in zip(two["peak_rss_mib"], fixed_peak["2x1"])]
res = {"mesh": mesh, "fixed_overhead_mib": fixed, "fixed_peak_mib": fixed_peak, "peak_per_rank_over_1_over_n_of_plain": peak_ratio, "variable_per_rank_over_1_over_n": var_ratio, "size": size, "spp": spp, "reference_spp": int(ref_spp), "runs": runs, "best": best,
       "efficiency_frame": eff_frame, "efficiency_quality": eff_quality, "plain": plain,
       "efficiency_vs_plain_frame": eff_plain_frame, "efficiency_vs_plain_quality": eff_plain_quality,
       "resident_per_rank_over_one": [m / one["resident_mib"][0] for m in two["resident_mib"]],
       "peak_per_rank_over_one": [m / one["peak_rss_mib"][0] for m in two["peak_rss_mib"]]}
json.dump(res, open(base + ".json", "w"), indent=1)
with open(base + ".md", "w") as f:
    f.write(f"# MPI mode: 1 rank x 2 PoCL threads vs 2 ranks x 1 thread ({mesh}, {size}, {spp} spp)\n\n")
    f.write("Fastest of the interleaved runs per configuration; load average (1 min) before/after each run in "
            "the JSON. Reference: one process, %s spp.\n\n" % ref_spp)
    f.write("| config | frame s | rel. RMSE | time to equal quality s | comm share per rank | peak MiB per rank "
            "| resident MiB per rank | elements per rank (owned) | load |\n|---|---|---|---|---|---|---|---|---|\n")
    for r in (one, two):
        f.write("| %s | %.4f | %.4f | %.2f | %s | %s | %s | %s | %.1f-%.1f |\n" % (
            r["config"], r["frame_s"], r["rel_rmse"], r["time_to_quality_s"],
            ", ".join("%.1f%%" % (100 * c) for c in r["comm_share"]),
            ", ".join("%.0f" % m for m in r["peak_rss_mib"]), ", ".join("%.0f" % m for m in r["resident_mib"]),
            ", ".join("%.0f (%.0f)" % (e, o) for e, o in zip(r["elements"], r["owned"])),
            r["load_before"], r["load_after"]))
    f.write("\nParallel efficiency (1x2 time / 2x1 time): per frame %.2f, to equal quality %.2f (goal 0.80).\n" %
            (eff_frame, eff_quality))
    f.write("Resident memory per rank over one process's: %s; peak: %s.\n" % (
        ", ".join("%.2f" % x for x in res["resident_per_rank_over_one"]),
        ", ".join("%.2f" % x for x in res["peak_per_rank_over_one"])))
    f.write("Fixed overhead per rank (resident on a 2k-element mesh, same configuration): 1x2 %s MiB, 2x1 %s MiB. "
            "Resident minus that, per rank, over 1/N of one process's: %s (goal 1.2).\n" % (
        ", ".join("%.0f" % x for x in fixed["1x2"]), ", ".join("%.0f" % x for x in fixed["2x1"]),
        ", ".join("%.2f" % x for x in var_ratio)))
    f.write("\nThe stricter baseline, one plain process (no mpirun) x 2 threads: frame %.4f s, rel. RMSE %.4f, "
            "time to equal quality %.2f s, peak %.0f MiB, resident %.0f MiB. Parallel efficiency of 2x1 against it: "
            "per frame %.2f, to equal quality %.2f.\n" % (plain["frame_s"], plain["rel_rmse"],
            plain["time_to_quality_s"], plain["peak_rss_mib"], plain["resident_mib"], eff_plain_frame,
            eff_plain_quality))
    f.write("Peak per rank less its fixed peak (%s MiB on the 2k-element mesh), over 1/N of the plain process's "
            "peak less %.0f MiB: %s (goal 1.2).\n" % (", ".join("%.0f" % x for x in fixed_peak["2x1"]),
            fixed_peak["1x2"][0], ", ".join("%.2f" % x for x in peak_ratio)))
    if mesh.endswith(".bin"):
        f.write("The .bin mesh is loaded in parts (each rank reads about 1/N of the file, docs/mpi-loading.md).\n")
    else:
        f.write("This input is loaded whole on every rank and cut (clvr_mpi_share_from_mesh): peak memory per "
                "rank holds the whole mesh once; a .bin file is loaded in parts.\n")
print(open(base + ".md").read())
PY
