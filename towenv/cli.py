"""Command-line interface: ``towenv scenes`` and ``towenv simulate SCENE``.

    towenv scenes
    towenv simulate two_part_tow_1 --duration 120 --out out/tpt1 --set vessel.speed=2.5

``simulate`` writes ``result.npz``, ``timeseries.csv``, ``summary.md``, ``summary.json`` and five PNG plots
into the output folder, each atomically, ``summary.md`` last (its presence marks a complete set). Bad
arguments, scene errors, an unusable output folder (checked before the run) and divergence print one line
to stderr and exit with code 2.
"""
from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import sys
import textwrap
import tomllib
from pathlib import Path

__all__ = ["main", "build_parser", "parse_override"]

EXIT_ERROR = 2


# ---------------------------------------------------------------------------------------------------
# argument helpers
# ---------------------------------------------------------------------------------------------------
def parse_value(text: str):
    """A ``--set`` value: a TOML literal (``2.5``, ``true``, ``"x"``, ``[1, 2]``, ``{a = 1}``), else JSON,
    else the raw text as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except (tomllib.TOMLDecodeError, KeyError):
        pass
    try:
        return json.loads(text)
    except ValueError:
        return text


def parse_override(text: str) -> tuple[str, object]:
    """``key=value`` -> ``(key, parsed value)`` (dotted scene path or solver setting)."""
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected key=value (e.g. vessel.speed=2.5), got {text!r}")
    return key, parse_value(value.strip())


def _fraction(text: str) -> float:
    v = _positive(text)
    if not v < 1:
        raise argparse.ArgumentTypeError(f"must be a relative tolerance in (0, 1), e.g. 0.05 (got {text})")
    return v


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0 (got {text})")
    return v


def _nonnegative(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (v >= 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0 (got {text})")
    return v


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="towenv", description="towenv: dynamic simulator of underwater towed systems.")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    ps = sub.add_parser("scenes", help="list the embedded scenes", description="List the embedded scenes.")
    ps.set_defaults(func=cmd_scenes)

    pm = sub.add_parser(
        "simulate", help="simulate a scene and write results, summary and plots",
        description="Simulate a scene and write result.npz, timeseries.csv, summary.md/json and PNG plots.",
        epilog="examples:\n  towenv simulate two_part_tow_1 --duration 120\n"
               "  towenv simulate my_scene.toml --set vessel.speed=2.5 --set 'bodies[fish].mass=45' --dt 0.01",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    pm.add_argument("scene", metavar="SCENE", help="embedded scene name (see `towenv scenes`) or path to a TOML file")
    pm.add_argument("--duration", type=_positive, default=120.0, help="simulated time in s (default 120)")
    pm.add_argument("--out", metavar="DIR", default=None,
                    help="output folder (default ./out/<scene>); checked before the run; files of an earlier run "
                         "there are replaced (a note says so), unless --no-overwrite")
    pm.add_argument("--no-overwrite", action="store_true",
                    help="refuse (exit 2) when the output folder already holds results of an earlier run")
    pm.add_argument("--dt", type=_positive, default=None, help="time step in s (overrides solver.dt)")
    pm.add_argument("--fidelity", type=_fraction, default=None, metavar="TOL",
                    help="choose dt, segments and 2-D/3-D automatically so the fish heave/pitch statistics stay "
                         "within TOL (relative, e.g. 0.05) of the fine default (docs/fidelity.md); without it, dt "
                         "alone is chosen (5 %%) when the scene does not set solver.dt")
    pm.add_argument("--discard", type=_nonnegative, default=None, metavar="SECONDS",
                    help="start-up window left out of the statistics (default max(ramp, 0.25 duration))")
    pm.add_argument("--set", dest="overrides", action="append", type=parse_override, default=[],
                    metavar="KEY=VALUE",
                    help="scene override by dotted path, value as a TOML/JSON literal (repeatable), "
                         "e.g. vessel.speed=2.5, lines.primary.length=90, solver.max_iterations=40")
    pm.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    pm.add_argument("--quiet", "-q", action="store_true",
                    help="no progress bar or summary table; print only the output folder")
    pm.set_defaults(func=cmd_simulate)

    pv = sub.add_parser("validate", help="run the validation cases and write docs/validation.md",
                        description="Run the validation report (same options as scripts/validate.py).",
                        add_help=False)
    pv.add_argument("rest", nargs=argparse.REMAINDER)
    pv.set_defaults(func=cmd_validate)
    return p


def cmd_validate(args) -> int:
    """``towenv validate [--quick] [--cases ...] [--report-only]``: the validation report."""
    from .validation.report import main as validate_main
    return int(validate_main(list(args.rest)) or 0)


def _one_line(exc: BaseException) -> str:
    """An exception message on one line (multi-problem scene errors joined with '; ')."""
    parts = [s.strip() for s in str(exc).splitlines() if s.strip()]
    if len(parts) > 1 and parts[0].endswith(":"):
        return parts[0] + " " + "; ".join(parts[1:])
    return "; ".join(parts) or type(exc).__name__


def _error(msg: str) -> int:
    print(f"towenv: error: {msg}", file=sys.stderr)
    return EXIT_ERROR


# ---------------------------------------------------------------------------------------------------
# commands
# ---------------------------------------------------------------------------------------------------
def cmd_scenes(args) -> int:
    from .scene import DEFAULT_SCENE, list_scenes
    scenes = list_scenes()
    if not scenes:
        print("no embedded scenes found")
        return 0
    width = max(60, min(shutil.get_terminal_size((110, 20)).columns, 140))
    nw = max(len(n) for n in scenes) + 2
    rows = [("SCENE", "DESCRIPTION")] + [(n + (" *" if n == DEFAULT_SCENE else ""), d or "-")
                                         for n, d in scenes.items()]
    nw = max(nw, max(len(r[0]) for r in rows))
    for i, (n, d) in enumerate(rows):
        wrapped = textwrap.wrap(d, width=max(30, width - nw - 2)) or [""]
        print(f"{n:<{nw}}  {wrapped[0]}")
        for cont in wrapped[1:]:
            print(f"{'':<{nw}}  {cont}")
        if i == 0:
            print(f"{'-' * nw}  {'-' * min(len('DESCRIPTION') + 20, width - nw - 2)}")
    print(f"\n* default scene. Run one with: towenv simulate {DEFAULT_SCENE} --duration 120")
    return 0


def _out_name(scene_arg: str, scene) -> str:
    from .scene import list_scenes
    if scene_arg in list_scenes():
        name = scene_arg
    else:
        name = Path(scene_arg).stem or getattr(scene, "name", "run")
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name) or "run"


#: the files `towenv simulate` writes; summary.md is written last and marks a complete set
OUTPUT_FILES = ("result.npz", "timeseries.csv", "summary.json", "summary.md")


def cmd_simulate(args) -> int:
    from .atomic import atomic_write, check_output_dir
    from .core.run import kernels_compiled, make_simulator, plan_records, simulate
    from .errors import SimulationDivergence
    from .report import default_discard, summarize, summary_markdown, write_timeseries_csv
    from .scene import SceneError

    overrides = dict(args.overrides)
    if args.dt is not None:
        overrides["dt"] = args.dt
    choice = None
    try:
        from .core.simulator import load
        from .fidelity import configure
        scene = load(args.scene)
        scene, choice = configure(scene, tolerance=args.fidelity, overrides=overrides)
        # one factory: the time integration named by solver.method (houbolt, generalized_alpha, euler, …)
        sim = make_simulator(scene, **overrides)
    except SceneError as exc:
        return _error(_one_line(exc))
    except ValueError as exc:                 # fidelity selection impossible for this scene
        return _error(_one_line(exc))
    except SimulationDivergence as exc:       # the initial static solution can fail too
        return _error(_one_line(exc))

    duration = float(args.duration)
    if args.discard is None:
        discard = default_discard(sim.scene, duration)
        if discard >= duration:
            print(f"towenv: warning: the run ({duration:g} s) is not longer than the start-up window "
                  f"({discard:g} s); statistics use the second half of the run", file=sys.stderr)
            discard = 0.5 * duration
    else:
        discard = float(args.discard)
    if discard >= duration:
        return _error(f"--discard ({discard:g} s) must be shorter than --duration ({duration:g} s)")
    # the run must fit in memory and leave >= 2 recorded samples for the statistics: checked before it starts
    every = max(1, int(round(0.05 / sim.dt)))
    try:
        n_steps, n_rec = plan_records(sim, duration, every)
    except ValueError as exc:
        return _error("--" + _one_line(exc))
    rec_dt = every * sim.dt
    kept = n_rec - max(0, math.ceil(discard / rec_dt - 1e-6))
    if kept < 2:
        return _error(f"--duration: {duration:g} s records {n_rec} sample(s), one every {rec_dt:g} s: fewer than the 2 "
                      f"the statistics need after the start-up window of {discard:g} s; use a longer --duration"
                      + (" or a shorter --discard" if args.discard is not None else ""))

    out = Path(args.out) if args.out else Path("out") / _out_name(args.scene, sim.scene)
    created = not out.exists()
    problem = check_output_dir(out)
    if problem:
        return _error(f"--out {out}: {problem}")
    earlier = [f for f in OUTPUT_FILES if (out / f).exists()]
    if earlier:
        if args.no_overwrite:
            return _error(f"--out {out}: holds the results of an earlier run ({', '.join(earlier)}); "
                          f"choose another folder or drop --no-overwrite")
        print(f"towenv: note: replacing the results of an earlier run in {out}", file=sys.stderr)

    if not args.quiet:
        print(f"simulating {sim.scene.name!r} for {duration:g} s (dt = {sim.dt:g} s)"
              + (f" with {', '.join(f'{k}={v!r}' for k, v in overrides.items())}" if overrides else ""),
              file=sys.stderr)
    if choice is not None and not args.quiet:
        print(f"fidelity: {choice.summary()} — {choice.reason} (docs/fidelity.md)", file=sys.stderr)
    if not args.quiet and not kernels_compiled():
        print("towenv: compiling the simulator kernels (first run after installing or updating: 20 s to 1.5 min of CPU, by machine; "
              "cached afterwards) — the progress bar starts moving once they are compiled", file=sys.stderr)
    try:
        res = simulate(sim, duration, progress=not args.quiet)
    except SimulationDivergence as exc:
        if created:                           # the folder made by the pre-run check: do not leave it empty
            try:
                out.rmdir()
            except OSError:
                pass
        return _error(_one_line(exc))
    res.meta["scene"] = sim.scene.name
    if overrides:
        res.meta["overrides"] = {k: v for k, v in overrides.items()}
    res.meta["discard"] = discard
    if choice is not None:
        res.meta["fidelity"] = choice.summary()

    # every file is written atomically (temporary name, then rename); the old summary — the completion mark
    # of the earlier set — goes first and the new one is written last, so an interrupted write never leaves
    # a folder that looks complete
    for f in ("summary.md", "summary.json"):
        (out / f).unlink(missing_ok=True)
    res.save(out / "result.npz")
    write_timeseries_csv(res, out / "timeseries.csv")
    summary = summarize(res, discard)
    if overrides:
        summary["overrides"] = {k: v for k, v in overrides.items()}
    if not args.no_plots:
        from .plots import save_all
        mean, heading, _ = sim.path.mean_path(res.t)
        save_all(res, out, discard=discard, track=(mean, heading))
    md = summary_markdown(summary, title=sim.scene.name)
    atomic_write(out / "summary.json", json.dumps(summary, indent=2, allow_nan=False, default=str) + "\n",
                 encoding="utf-8")
    atomic_write(out / "summary.md", md, encoding="utf-8")

    if not args.quiet:
        print(md)
    print(f"output written to {out.resolve()}")
    return 0


# ---------------------------------------------------------------------------------------------------
def main(argv=None) -> int:
    """Entry point of the ``towenv`` command; returns the exit code (0 ok, 2 on errors)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["validate"]:                 # options pass straight through to the validation report
        from .validation.report import main as validate_main
        return int(validate_main(argv[1:]) or 0)
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_ERROR
    return int(args.func(args) or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
