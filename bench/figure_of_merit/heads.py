#!/usr/bin/python3
"""Issue 23: the cost of a flowing second, the published protocol at full size against the
small-head steady state, at D = 3.1 and 3.5 cm, theta = 45 deg, the calibrated model with the
growing shakes (bench/figure_of_merit/README.md, "Heads").

usage: heads.py CAMPAIGN_EXE [--heads 300 700 1500] [--lids 0 22] [--D 3.1 3.5] [--out DIR]
                [--short 5 --long 25] [--no-published]

Every run is one `campaign simulate` of a sweep written here, timed by its CPU time (user +
system of the process, from os.wait4: robust to a shared machine, unlike wall time):
  - published: one full realization per outlet (fill, settle, discharge to empty with its jams
    and shakes): core-seconds per flowing second = CPU / flowing time (the discharge time, the
    time the hopper was jammed excluded), fill and settle included;
  - steady state: per head, lid (`protocol.lid_gravity`, issue 40; 0: none) and outlet, a short
    and a long realization (max_time_s = SHORT and LONG s of discharge, no jam limit): the marginal cost of a flowing second is the CPU
    difference over the flowing-time difference (the fill and settle cancel: a long campaign
    amortises them), the intercept what one fill and settle costs.
Jams per core-hour = (jams per flowing second) x (flowing seconds per core-hour); where the jam
rate is the same in both protocols (docs/clogging.md, the head scan) the ratio of jams per
core-hour is the ratio of flowing seconds per core-hour, which this prints. Writes DIR/heads.json.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

BASE = """[hopper]
width_cm = 43.0
particles = {N}
[material]
collision_time_s = 8.0e-4
e_n = 0.5
mu = 0.8
[walls]
spacing = 0.5
edge_offset = 0.15
e_n = 0.5
mu = 0.8
[integrator]
scheme = "gear4"
steps_per_collision = 50
contact_corrections = false
[protocol]
shake_growth = 1.5
shake_amplitude_max = 1.0
max_shakes = 50
max_time_s = {T}
{extra}"""


def run(exe, text, D, seed, workdir, name):
    path = os.path.join(workdir, name + ".toml")
    with open(path, "w") as fh:
        fh.write(text)
    p = subprocess.Popen([exe, "simulate", path, "--D", str(D), "--theta", "45", "--seed",
                          str(seed), "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = p.communicate()
    if p.returncode not in (0, 3):
        sys.exit("heads.py: %s failed (exit %d): %s" % (name, p.returncode, err.decode()[-400:]))
    r = json.loads(out)
    return r


def cpu_of(exe, text, D, seed, workdir, name):
    before = os.times()
    r = run(exe, text, D, seed, workdir, name)
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system -
                                                            before.children_system)
    jammed = 0.0
    ev = r.get("events", [])
    # flowing time: the discharge time less the jammed periods (jam onset to restart)
    td_end = r["empty_time"] if r.get("empty_time") is not None else max(
        [e["time"] for e in ev] + [0.0])
    onsets = r.get("jam_onsets", [])
    restarts = [e["time"] for e in ev if e["kind"] == "flow_restart"]
    for k, on in enumerate(onsets):
        off = restarts[k] if k < len(restarts) else td_end
        jammed += max(0.0, off - on)
    return {"name": name, "cpu_s": cpu, "discharge_s": td_end, "flowing_s": td_end - jammed,
            "jams": r["n_jams"], "shakes": r["n_shakes"], "status": r["status"],
            "particle_steps": r["diagnostics"]["particle_steps"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("exe")
    ap.add_argument("--heads", type=int, nargs="*", default=[300, 700, 1500])
    ap.add_argument("--lids", type=float, nargs="*", default=[0.0],
                    help="protocol.lid_gravity of the steady states (0: no lid)")
    ap.add_argument("--D", type=float, nargs="*", default=[3.1, 3.5])
    ap.add_argument("--short", type=float, default=5.0)
    ap.add_argument("--long", type=float, default=25.0)
    ap.add_argument("--no-published", action="store_true")
    ap.add_argument("--out", default=".")
    args = ap.parse_args()
    if any(lid < 0 for lid in args.lids):
        sys.exit("heads.py: --lids must be >= 0 (0: no lid), got %s" % args.lids)
    work = tempfile.mkdtemp(prefix="heads_")
    rows = []
    for D in args.D:
        if not args.no_published:
            r = cpu_of(args.exe, BASE.format(N=8750, T=600.0, extra=""), D, 1, work,
                       "published_D%s" % D)
            r.update({"D_cm": D, "protocol": "published", "particles": 8750,
                      "core_s_per_flowing_s": r["cpu_s"] / r["flowing_s"]})
            rows.append(r)
            print(json.dumps(r), flush=True)
        for N in args.heads:
            for lid in args.lids:
                ss = 'mode = "steady_state"\n' + ("lid_gravity = %r\n" % lid if lid else "")
                tag = "steady_N%d%s_D%s" % (N, "_lid%g" % lid if lid else "", D)
                a = cpu_of(args.exe, BASE.format(N=N, T=args.short, extra=ss), D, 1, work,
                           tag + "_short")
                b = cpu_of(args.exe, BASE.format(N=N, T=args.long, extra=ss), D, 1, work,
                           tag + "_long")
                slope = (b["cpu_s"] - a["cpu_s"]) / (b["flowing_s"] - a["flowing_s"])
                r = {"D_cm": D, "protocol": "lid" if lid else "steady_state", "particles": N,
                     "lid_gravity": lid, "short": a, "long": b, "core_s_per_flowing_s": slope,
                     "fill_and_settle_core_s": a["cpu_s"] - slope * a["flowing_s"]}
                rows.append(r)
                print(json.dumps(r), flush=True)
    print("\n%-6s %-13s %6s %5s %22s %24s %10s" % (
        "D (cm)", "protocol", "N", "lid", "core-s / flowing s", "flowing s / core-hour",
        "vs published"))
    for D in args.D:
        pub = [r for r in rows if r["D_cm"] == D and r["protocol"] == "published"]
        ref = 3600 / pub[0]["core_s_per_flowing_s"] if pub else None
        for r in [x for x in rows if x["D_cm"] == D]:
            per_h = 3600 / r["core_s_per_flowing_s"]
            r["flowing_s_per_core_hour"] = per_h
            r["ratio_to_published"] = per_h / ref if ref else None
            print("%-6s %-13s %6d %5s %22.3f %24.0f %10s" % (
                D, r["protocol"], r["particles"], "%g" % r["lid_gravity"] if r.get("lid_gravity")
                else "-", r["core_s_per_flowing_s"], per_h,
                "%.1fx" % r["ratio_to_published"] if ref else "-"))
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "heads.json"), "w") as fh:
        json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
