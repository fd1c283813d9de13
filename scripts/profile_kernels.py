"""Where the compiled simulator spends its time: sample a run with Linux ``perf`` and attribute each sample to the
numba-compiled function it fell in (issue 15's profile, docs/architecture.md "Where the time goes").

numba's kernels are JIT code without symbols perf can see, so the run dumps, at its end and from the same process,
the address of every function in the compiled library of ``houbolt.advance`` (numba's ``library``); each sampled
instruction pointer is then given to the function with the nearest start below it (bisect). Samples outside the
library (Python, numpy, the compiler during the warm-up) are counted as "outside".

    python scripts/profile_kernels.py                                  # two_part_coastal_ss4, Δt 0.05 s
    python scripts/profile_kernels.py --scene two_part_tow_1 --seconds 40000 --top 15

Needs ``perf`` (linux-tools) with permission to sample this process (perf_event_paranoid ≤ 2); says so if missing.
The shares are of the samples inside the library, whose own share is printed too. Host-dependent: compare shares
measured on the same machine.
"""
from __future__ import annotations

import argparse
import bisect
import collections
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile


def short_name(mangled: str) -> str:
    """``module.function`` from numba's Itanium-style mangled name (``_ZN6towenv4core7houbolt7advanceB3v18…`` →
    ``houbolt.advance``); the mangled name itself when it does not parse."""
    m = re.search(r"_ZN((?:\d+[A-Za-z_][A-Za-z0-9_]*)+)", mangled)
    if not m:
        return mangled[:60]
    parts, s = [], m.group(1)
    while s and s[0].isdigit():
        n = re.match(r"\d+", s).group(0)
        parts.append(s[len(n):len(n) + int(n)])
        s = s[len(n) + int(n):]
    prefix = "cpython wrapper of " if mangled.startswith(("_ZN7cpython", "cfunc.")) else ""
    parts = [p for p in parts if p not in ("cpython",)]
    return prefix + ".".join(parts[-2:])


def attribute(ips, symbols: dict) -> tuple[collections.Counter, int]:
    """(samples per short function name inside the library, samples outside) for instruction pointers ``ips`` and
    ``symbols`` (mangled name -> start address); a sample belongs to the nearest start at or below it, within 1 MB."""
    items = sorted((a, k) for k, a in symbols.items())
    starts = [a for a, _k in items]
    inside, outside = collections.Counter(), 0
    for ip in ips:
        i = bisect.bisect_right(starts, ip) - 1
        if i >= 0 and ip - starts[i] < (1 << 20):
            inside[short_name(items[i][1])] += 1
        else:
            outside += 1
    return inside, outside


def _child(a) -> int:
    """The sampled run: warm up (compile), advance, then dump the library's function addresses (empty if the kernels
    came from numba's on-disk cache: the parent points NUMBA_CACHE_DIR at an empty folder)."""
    import towenv
    from towenv.core import houbolt
    sim = towenv.make_simulator(a.scene, dt=a.dt)
    sim.advance(a.dt * 20)
    sim.advance(a.seconds)
    syms = {}
    for cres in houbolt.advance.overloads.values():
        lib = cres.library
        mod = getattr(lib, "_final_module", None)
        for f in (mod.functions if mod is not None else ()):
            if f.is_declaration:
                continue
            try:
                addr = lib.get_pointer_to_function(f.name)
            except Exception:       # noqa: BLE001 - a function the engine did not emit
                addr = 0
            if addr:
                syms[f.name] = int(addr)
    with open(a.child, "w") as fh:
        json.dump(syms, fh)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="two_part_coastal_ss4", help="packaged scene (default two_part_coastal_ss4)")
    ap.add_argument("--dt", type=float, default=0.05, help="time step, s (default 0.05)")
    ap.add_argument("--seconds", type=float, default=20000.0,
                    help="simulated seconds sampled (default 20000: a few s of CPU)")
    ap.add_argument("--frequency", type=int, default=2000, help="perf sampling frequency, Hz (default 2000)")
    ap.add_argument("--top", type=int, default=20, help="functions listed (default 20)")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if not a.dt > 0 or not a.seconds > 0 or not a.frequency > 0 or not a.top > 0:
        ap.error("--dt, --seconds, --frequency and --top must be positive")
    if a.child:
        return _child(a)
    perf = shutil.which("perf")
    if perf is None:
        print("profile_kernels: `perf` is not installed (linux-tools); nothing sampled", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        data, syms = os.path.join(tmp, "perf.data"), os.path.join(tmp, "symbols.json")
        cmd = [perf, "record", "-q", "-F", str(a.frequency), "-o", data, "--", sys.executable, os.path.abspath(__file__),
               "--scene", a.scene, "--dt", repr(a.dt), "--seconds", repr(a.seconds), "--child", syms]
        # a fresh numba cache: a library loaded from the on-disk cache keeps no module to read the addresses from, so
        # the sampled run compiles its kernels itself (20 s to 1.5 min, outside the library's samples)
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, "numba_cache"))
        r = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if r.returncode != 0 or not os.path.exists(syms):
            print(f"profile_kernels: perf record failed (exit {r.returncode}):\n{r.stderr.strip()[-2000:]}",
                  file=sys.stderr)
            return 2
        out = subprocess.run([perf, "script", "-F", "ip", "-i", data], capture_output=True, text=True)
        ips = []
        for line in out.stdout.split():
            try:
                ips.append(int(line, 16))
            except ValueError:
                pass
        with open(syms) as fh:
            symbols = json.load(fh)
    inside, outside = attribute(ips, symbols)
    n_in = sum(inside.values())
    total = n_in + outside
    if n_in == 0:
        print(f"profile_kernels: none of {total} samples fell in the compiled library", file=sys.stderr)
        return 2
    print(f"{a.scene}, dt {a.dt:g} s, {a.seconds:g} s simulated: {total} samples, {100 * n_in / total:.1f} % inside "
          f"the compiled library of houbolt.advance (the rest: warm-up compile, Python, numpy)")
    for name, c in inside.most_common(a.top):
        print(f"{100 * c / n_in:6.1f} %  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
