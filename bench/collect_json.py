#!/usr/bin/env python3
"""collect_json.py RUNS.tsv OUT.json KEY=VALUE...: one JSON report for one device.

RUNS.tsv has a line per benchmark: name, exit status, seconds, its --json file, its
output log. The report is {KEY: VALUE..., "benchmarks": [{"name", "exit", "seconds",
"result" (the benchmark's own JSON object, or null), "error" (why not)}]}.
"""
import json
import os
import sys


def main(argv):
    runs_path, out_path, pairs = argv[1], argv[2], argv[3:]
    report = {}
    for pair in pairs:
        key, _, value = pair.partition("=")
        report[key] = value
    benches = []
    with open(runs_path) as f:
        for line in f:
            name, rc, secs, json_path, log_path = line.rstrip("\n").split("\t")
            entry = {"name": name, "exit": int(rc), "seconds": float(secs), "result": None}
            if os.path.exists(json_path):
                try:
                    with open(json_path) as jf:
                        entry["result"] = json.load(jf)
                except (OSError, ValueError) as e:
                    entry["error"] = f"--json output is not JSON: {e}"
            else:
                entry["error"] = "wrote no --json file"
            if int(rc) != 0:
                with open(log_path, errors="replace") as lf:
                    entry["log_tail"] = lf.read()[-4000:]
            benches.append(entry)
    report["benchmarks"] = benches
    with open(out_path, "w") as f:
        json.dump(report, f, indent=1)
        f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
