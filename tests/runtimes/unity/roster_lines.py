#!/usr/bin/env python3
"""roster_lines.py ROSTER.json - the roster's types, clips (timed rows), contacts, states and sockets, one line
each, in the line format of CrowdbakeCheck.exe's `roster` mode: Python's json reads the manifest
that the Unity package's C# reader must equal (tests/runtimes/test_unity_cs.c)."""
import json
import sys


def main(path):
    doc = json.load(open(path, encoding="utf-8"))
    out = []
    for name, t in doc["types"].items():
        out.append(["T", name, t["palette"], t["layout"], t["precision"], t["bones"], t["rows"], t["speed_reference"],
                    t["default_state"]])
        for c in t["clips"]:
            out.append(["L", name, c["name"], c["first_row"], c["frame_count"], c["fps"], c["duration"], int(c["loops"]),
                        c["ground_speed"]])
            if "timed_rows" in c:  # a timed clip (.pal version 7): its map's cells, their rate, its map rows
                r = c["timed_rows"]
                out.append(["R", name, c["name"], r["cells"], r["cell_rate"], r["map_rows"]])
            for k in c.get("contacts", []):
                out.append(["K", name, c["name"], k["foot"], k["bone"], k["time"], k["lift"]])
        for s, st in t["states"].items():
            i = st["instance"]
            out.append(["S", name, s, st["clip"], i["first_row"], i["frame_count"], i["rate"], i["rate_per_speed"], i["phase"]])
        for k in t.get("sockets", []):
            out.append(["O", name, k["name"], k["bone"]] + k["bind_transform"])
    for line in out:
        print(" ".join(repr(v) if isinstance(v, float) else str(v) for v in line))


if __name__ == "__main__":
    main(sys.argv[1])
