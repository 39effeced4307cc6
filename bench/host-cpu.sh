#!/usr/bin/env bash
# bench/host-cpu.sh: one line naming this machine's CPU for a benchmark's header:
# model name, vendor, family / model / stepping, hypervisor and cache sizes (lscpu,
# else /proc/cpuinfo's model name, else "unknown CPU"). A VM's model name alone
# ("Intel(R) Xeon(R) Processor") does not tell two kinds of machine apart: sessions
# 54 and 61 measured the same code 1.43x and 1.61x Embree on "an Intel Xeon VM", and
# the results could not say whether it was the same kind.
set -u
line=$(LC_ALL=C lscpu 2>/dev/null | awk -F: '
  /^(Model name|Vendor ID|CPU family|Model|Stepping|Hypervisor vendor|L2 cache|L3 cache):/ {
    v = $2; gsub(/^ +| +$/, "", v); f[$1] = v }
  END {
    if (!("Model name" in f)) exit
    s = f["Model name"]
    if ("Vendor ID" in f) s = s ", " f["Vendor ID"]
    if ("CPU family" in f) s = s ", family " f["CPU family"] " model " f["Model"] " stepping " f["Stepping"]
    if ("Hypervisor vendor" in f) s = s ", under " f["Hypervisor vendor"]
    if ("L2 cache" in f) s = s ", L2 " f["L2 cache"]
    if ("L3 cache" in f) s = s ", L3 " f["L3 cache"]
    print s }')
[ -n "$line" ] || line=$(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo 2>/dev/null)
echo "${line:-unknown CPU}"
