"""Hover et al. (1994) deep tow (Table II, Fig. 2 conditions): how much the two readings of the paper change
the towfish heave response (issue 18, item 4, first part).

The paper: "The top of the cable was excited by a one-meter sinusoid, and U = 0 uniformly", with Table II's
parameters. Two things are open to reading:

* **w0.** Table II prints w0 = 8.14 N/m, but its mass (1.04 kg/m) and diameter (0.0173 m) give
  (m − ρπd²/4) g = 7.83 N/m. The scene keeps the printed mass and diameter; the other reading raises the
  mass per length to 8.14/g + ρπd²/4 (same diameter, so the same drag).
* **"one-meter sinusoid".** An amplitude of 1 m or a height (peak to peak) of 1 m, i.e. amplitude 0.5 m.
  With quadratic drag the response depends on the amplitude. The paper's second example says of the same
  kind of excitation ("a one-meter axial excitation") that "−30 dB in Q or P means a six-centimeter
  peak-to-peak oscillation": −30 dB of a 1 m amplitude is 3.2 cm amplitude, 6.3 cm peak to peak — the
  amplitude reading (a 1 m height would give 3.2 cm peak to peak).

For each of the four combinations this runs the time-domain simulator at a grid of frequencies (the
validation's planar deep-tow scene and harmonic analysis, towenv.validation.hover) and the linearised model
(harmonic equivalent linearisation at that amplitude, fine grid), and reports the heave response Q = |fish
heave| / |top heave|, its peak, the fish-end tension amplitude and whether the secondary end goes slack. It
compares nothing with the paper's withheld Fig. 2.

    python scripts/hover_readings.py                 # ~2 min; writes runs/hover_readings/
    python scripts/hover_readings.py --quick         # 4 frequencies
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="4 frequencies instead of 12")
    ap.add_argument("--out-dir", default="runs/hover_readings", help="output folder (default: %(default)s)")
    a = ap.parse_args(argv)
    from tqdm import tqdm

    from towenv.validation import hover as H

    omegas = [0.4, 0.8, 1.0, 1.4] if a.quick else list(H.READING_OMEGAS)

    class _Bar:
        def __init__(self):
            self.t = tqdm(total=len(H.DEEP_TOW_READINGS) * len(omegas), desc="deep-tow readings", unit="run")

        def step(self, label=""):
            self.t.set_postfix_str(label)
            self.t.update()
    bar = _Bar()
    rows = H.deep_tow_readings(omegas, bar)
    bar.t.close()

    lines = ["# Hover et al. deep tow: sensitivity of the towfish heave response to the two readings", "",
             "Command: `python scripts/hover_readings.py" + (" --quick" if a.quick else "") + "`. Q = |fish heave| / "
             "|top heave| (harmonic analysis of the last four periods); linear = towenv.linear at that amplitude; "
             "Hover = the paper's appendix model with its equal-dissipation drag linearisation.", "",
             "| reading | w0 (N/m) | amplitude (m) | time-domain peak: ω (rad/s), Q | linear peak: ω, Q | Hover peak: ω, Q "
             "| fish-end slack at ω |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['reading']} | {r['w0']:.2f} | {r['amplitude']:.1f} | {r['time_domain_peak']['omega']:.2f}, "
                     f"{r['time_domain_peak']['Q']:.3f} | {r['linear_peak']['omega']:.2f}, {r['linear_peak']['Q']:.3f} | "
                     f"{r['closed_form_peak']['omega']:.2f}, {r['closed_form_peak']['Q']:.3f} | "
                     f"{', '.join(f'{w:g}' for w in r['slack_at']) or 'none'} |")
    lines += ["", "Time-domain Q per frequency:", "",
              "| ω (rad/s) | " + " | ".join(r["reading"] for r in rows) + " |",
              "|---|" + "---|" * len(rows)]
    for i, om in enumerate(omegas):
        lines.append(f"| {om:g} | " + " | ".join(f"{r['time_domain'][i]['Q']:.3f}" for r in rows) + " |")
    text = "\n".join(lines) + "\n"
    print(text)

    out = Path(a.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    for r, c in zip(rows, ("C0", "C1", "C2", "C3")):
        ax.plot(r["linear"]["omega"], r["linear"]["Q"], color=c, lw=1.2, label=f"{r['reading']} (linear)")
        ax.plot([x["omega"] for x in r["time_domain"]], [x["Q"] for x in r["time_domain"]], "o", color=c, ms=4)
    ax.set_xlabel("ω (rad/s)")
    ax.set_ylabel("Q = |fish heave| / |top heave|")
    ax.set_title("Hover deep tow: readings of w0 and of 'one-meter sinusoid' (dots: time domain)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    for name, write in (("readings.md", lambda p: p.write_text(text)),
                        ("readings.json", lambda p: p.write_text(json.dumps(rows, indent=1))),
                        ("readings.png", lambda p: fig.savefig(p, dpi=120, format="png"))):
        tmp = out / f".{name}.{os.getpid()}.tmp"
        write(tmp)
        os.replace(tmp, out / name)
    print(f"wrote {out}/readings.md, readings.json, readings.png", file=sys.stderr)


if __name__ == "__main__":
    main()
