"""A stand-in implementation for the runner's tests: it answers every scan with the
observations the vector expects (read from the vector files), and misbehaves on request.

    python oracle_adapter.py VECTOR_DIR MODE

MODE: ``good``; ``exit3`` (exits when the third vector of its life is reset);
``sleep`` (never answers the first scan of the second vector); ``garbage`` (prints a
line that is not JSON instead of the second vector's first answer); ``flood`` (prints
100 MB without a line end at the second vector); ``slow`` (waits 0.2 s before every
answer); ``wrong`` (DN inverted in the second scan of every vector that has a tag);
``silent`` (never answers hello); ``error`` (answers reset with an error).
"""

import json
import sys
import time
from pathlib import Path


def main() -> int:
    directory, mode = Path(sys.argv[1]), sys.argv[2]
    vectors = {}
    for p in directory.glob("*.json"):
        if p.name != "manifest.json":
            doc = json.loads(p.read_text(encoding="utf-8"))
            vectors[doc["id"]] = doc
    resets = 0
    current = None
    out = sys.stdout
    for line in sys.stdin:
        msg = json.loads(line)
        kind = msg["type"]
        if kind == "hello":
            if mode == "silent":
                time.sleep(3600)
            answer = {"type": "hello", "protocol": msg["protocol"], "implementation": {"name": f"oracle-{mode}"},
                      "supports": {"axis_families": ["AxisNonCIP", "AxisCIP"],
                                   "instructions": ["MSO", "MSF", "MASD", "MASR", "MAFR", "MDO", "MDF", "MDS", "MRHD"],
                                   "observables": {"*": ["*"]}}}
        elif kind == "reset":
            resets += 1
            if mode == "exit3" and resets == 3:
                print("oracle: exiting on purpose", file=sys.stderr)
                return 3
            if mode == "error":
                answer = {"type": "error", "message": "this set-up is not supported"}
            else:
                current = vectors[msg["vector"]]
                answer = {"type": "ready", "observations": current["initial"]}
        elif kind == "scan":
            k = msg["index"]
            if resets == 2 and k == 0:
                if mode == "sleep":
                    time.sleep(3600)
                if mode == "garbage":
                    out.write("this is not JSON\n")
                    out.flush()
                    continue
                if mode == "flood":
                    chunk = "x" * (1 << 20)
                    try:
                        for _ in range(100):
                            out.write(chunk)
                        out.flush()
                    except BrokenPipeError:
                        return 1
                    continue
            obs = json.loads(json.dumps(current["scans"][k]["expect"]))
            if mode == "wrong" and k == 1:
                for _name, fields in obs.items():
                    if "DN" in fields:
                        fields["DN"] = not fields["DN"]
                        break
            answer = {"type": "observations", "index": k, "observations": obs}
        elif kind == "bye":
            return 0
        else:
            answer = {"type": "error", "message": f"unknown message {kind}"}
        if mode == "slow":
            time.sleep(0.2)
        out.write(json.dumps(answer) + "\n")
        out.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
