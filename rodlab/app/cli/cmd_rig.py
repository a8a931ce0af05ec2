"""``rodlab rig fit|simulate|acquire``: the stiffness rig (core install only; no CAD stack needed)."""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

from rodlab.stiffness_rig import RigError, fit_recording, plot_fit, read_recording
from rodlab.stiffness_rig.effects import RIG_EFFECTS, joint_places, rig_effect
from rodlab.stiffness_rig.fit import noise_text, r_rod_note
from rodlab.stiffness_rig.fit_checks import load_scale_problems
from rodlab.stiffness_rig.plan_check import default_masses, linear_range_warnings
from rodlab.stiffness_rig.plot import format_pm, format_zero

from ...core.compliance import write_compliance
from ...core.design_io import resolve_design
from ...core.enums import Checksum, LineProtocol, LoadAxis
from ...core.sensitivity import STRUCTURAL_ENTRIES
from ...core.errors import RodlabError
from ...core.progress import progress as bar_of
from .argtypes import count, nonneg_float, pos_float, seed
from .interrupts import kill_as_interrupt
from .effectargs import effects_help, parse_effect_specs
from .reporting import add_report_option, png_file, write_command_report
from .rig_served import profile_simulators
from .rodargs import compliance_arg, design_of_compliance, same_rod

__all__ = ["register"]


def register(sub) -> None:
    rig = sub.add_parser("rig", help="stiffness rig: acquire, simulate and fit recordings",
                         description="The stiffness rig of the paper (Fig. 7): hang weights on the rod, record the "
                                     "ball's displacement, fit the compliance.")
    rsub = rig.add_subparsers(dest="rig_command", metavar="RIG_COMMAND")
    _register_fit(rsub)
    _register_simulate(rsub)
    _register_acquire(rsub)
    _register_simulator(rsub)
    rig.set_defaults(func=lambda a: (rig.print_help(), 1)[1])


def _register_fit(rsub) -> None:
    p = rsub.add_parser("fit", help="fit a recording: measured C_F, r_rod (Eq. 21), measured compliance file",
                        description="Hold averages, one line per load axis and branch, intercepts in kg, measured "
                                    "C_F, r_rod against the simulated compliance, C_g = r_rod C_g_sim (Eq. 22).")
    p.add_argument("recording", help="*.rig.csv")
    p.add_argument("--sim", required=True, help="simulated compliance file (fea or calc), or a design (rod1, "
                                                "my.rod.toml: its closed-form compliance)")
    p.add_argument("-o", "--output", required=True, help="measured *.compliance.json")
    p.add_argument("--png", default=None, help="the paper's Fig. 8 for this recording: FILE.png, or a folder (it "
                                               "gets fig8.png)")
    p.add_argument("--robust", action="store_true", help="soft-L1 loss: outlying holds lose weight")
    p.add_argument("--load", choices=("cell", "mass"), default="cell",
                   help="the load of each hold: the load cell's force_N where the recording has one (cell, the "
                        "default), or mass_kg x g0 of the hung masses (mass: a load cell that read in another unit)")
    add_report_option(p)
    p.set_defaults(func=cmd_fit)


def _register_simulate(rsub) -> None:
    p = rsub.add_parser("simulate", help="write a recording from the rig's physical model (no hardware)",
                        formatter_class=argparse.RawDescriptionHelpFormatter,
                        description="Simulate the stiffness rig on a rod with a known compliance and optional "
                                    "effects, the contract's protocol by default. Effects and their parameters "
                                    "(defaults: a typical magnitude):\n" + rig_effects_help())
    p.add_argument("--sim", required=True, help="the rod's compliance file (its C_F is the truth), or a design (rod1, "
                                            "my.rod.toml: its closed-form compliance)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                   help="add an effect, e.g. friction:F_f_N=0.3, creep:phi=0.03,tau_s=5 or "
                        "joint_compliance:location=pipe_II,s_bend_rad_per_Nm=5e-6 (repeatable)")
    p.add_argument("--design", default=None, help="the rod's design (*.rod.toml or a built-in name) to place "
                                                  "joint springs exactly (default: guessed from the tool vector)")
    p.add_argument("--axes", default="y,z,x", help="load axes in order (default y,z,x)")
    p.add_argument("--masses", default=None,
                   help="masses [kg], e.g. 0.5,1.0,1.5,2.0 (default: the paper's 0.5,1.0,1.5,2.0; on a carbon rod "
                        "those within its 15 N linear range, 0.5,1.0,1.5)")
    p.add_argument("--repeats", type=count, default=5, help="load-unload cycles per axis (default 5)")
    p.add_argument("--hold-s", type=pos_float, default=8.0, help="duration of each hold [s] (default 8)")
    p.add_argument("--rate-hz", type=pos_float, default=10.0, help="gauge sample rate [Hz] (default 10)")
    p.add_argument("--noise-um", type=nonneg_float, default=0.6, help="per-reading noise SD [um] (default 0.6)")
    p.add_argument("--load-cell-noise-n", type=nonneg_float, default=None, metavar="SD_N",
                   help="add a load cell between the loading frame and the rod with this noise SD [N]: the "
                        "recording gets a force_N column (the force the rod carries, friction and tare included)")
    p.add_argument("--seed", type=seed, default=0, help="random seed of the noise and effects (default 0)")
    p.add_argument("-o", "--output", required=True, help="*.rig.csv")
    p.set_defaults(func=cmd_simulate)


def _register_acquire(rsub) -> None:
    p = rsub.add_parser("acquire", help="record a plan from the rig (prompts the operator or commands a loader)",
                        description="Run an acquisition plan on the rig described by the profile; every sample is "
                                    "appended and flushed as it arrives; re-running the same command resumes after "
                                    "the last complete hold.")
    p.add_argument("--profile", required=True, help="rig profile TOML (port, protocol, channels)")
    p.add_argument("--plan", required=True, help="acquisition plan TOML (axes, masses, repeats, holds)")
    p.add_argument("-o", "--output", required=True, help="*.rig.csv (appended to; resumable)")
    p.add_argument("--non-interactive", action="store_true",
                   help="command the loader of the profile instead of prompting the operator")
    p.add_argument("--new-file", action="store_true",
                   help="never continue an existing file: record into the next free name beside it (run-2.rig.csv)")
    p.add_argument("--design", default=None, help="the rod's design (*.rod.toml or a built-in name), to warn about "
                                                  "loads beyond a carbon rod's linear range (default: the plan's rod "
                                                  "when it is a built-in)")
    p.set_defaults(func=cmd_acquire)


def _register_simulator(rsub) -> None:
    p = rsub.add_parser("simulator", help="serve a simulated rig on a pseudo-terminal (until Ctrl-C)",
                        description="Stand-in for the real rig: a gauge counter (query or stream protocol) and a "
                                    "commandable loader on a pty, published at --link; point a profile's port at it.")
    p.add_argument("--sim", required=True, help="the rod's compliance file (its C_F is the truth), or a design (rod1, "
                                            "my.rod.toml: its closed-form compliance)")
    p.add_argument("--link", default=None, help="path of the symlink to the pty (the profile's port)")
    p.add_argument("--profile", default=None, help="a rodlab.rigprofile/2 profile: serve every instrument of it "
                                                   "(its protocol, channels, units) under --link-dir")
    p.add_argument("--link-dir", default=None, help="with --profile: the folder of the instruments' pty links "
                                                    "(one per instrument name) and of sim.profile.toml, the "
                                                    "profile with its ports pointed at them")
    p.add_argument("--load-cell-noise-n", type=nonneg_float, default=0.005, metavar="SD_N",
                   help="with --profile: the simulated load cell's noise SD [N] (default 0.005)")
    p.add_argument("--protocol", choices=[m.value for m in LineProtocol], default=LineProtocol.QUERY.value,
                   help=f"the line protocol the simulated gauges speak (default {LineProtocol.QUERY.value})")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                   help="add an effect (as for rig simulate; repeatable)")
    p.add_argument("--design", default=None, help="the rod's design, to place joint springs exactly")
    p.add_argument("--checksum", choices=[m.value for m in Checksum], default=Checksum.NONE.value,
                   help=f"checksum appended to each answer (default {Checksum.NONE.value})")
    p.add_argument("--garbage", type=nonneg_float, default=0.0, help="probability of a garbage line per answer")
    p.add_argument("--seconds", type=nonneg_float, default=0.0, help="stop after this many seconds (0: until Ctrl-C)")
    p.set_defaults(func=cmd_simulator)


def _load_cell_left_out(rec, sim, args) -> dict:
    """``--load mass``: what the load cell said (its scale per load axis, what was wrong with it) before it is left
    out, for the provenance of the file written, and the note on stderr."""
    try:
        cell = fit_recording(rec, sim, robust=args.robust)
    except RigError as e:               # readings no fit takes (absurd forces): left out all the same
        said = f"the fit on its readings was refused: {e.detail}"
        print(f"note: {args.recording}: the load cell's force_N is left out; the loads are mass_kg x g0 ({said})",
              file=sys.stderr)
        return {"scale": [], "problems": [said]}
    refused, warned = load_scale_problems(cell.load)
    print(f"note: {args.recording}: the load cell's force_N is left out; the loads are mass_kg x g0"
          + (f" (the load cell: {(refused + warned)[0]})" if refused + warned else ""), file=sys.stderr)
    return {"scale": [sc.to_dict() for sc in (cell.load.scale if cell.load else ())], "problems": refused + warned}


def cmd_fit(args: argparse.Namespace) -> int:
    rec = read_recording(args.recording)
    sim = compliance_arg(args.sim)
    if rec.rod and sim.rod and not same_rod(rec.rod, sim.rod):    # the file written would mix the two rods
        raise RodlabError(f"{args.recording} is of rod {rec.rod!r} (its '# rod:' line) and --sim {args.sim} of rod "
                          f"{sim.rod!r}: the measured compliance file would hold one rod's measurement with the other's "
                          f"mass, centre of mass and tool. Give --sim this rod's simulation (rodlab fea <its design> -o "
                          f"FILE), or correct the recording's '# rod:' line if it names the wrong rod")
    left_out = None
    if args.load == "mass" and rec.has_force:
        left_out = _load_cell_left_out(rec, sim, args)
        rec = dataclasses.replace(rec, force_N=None)
    fit = fit_recording(rec, sim, robust=args.robust)
    if not fit.success:
        raise RodlabError(f"{args.recording}: {fit.message}")
    comp = fit.compliance(sim, rec)
    if left_out is not None:
        comp.provenance["load_cell_left_out"] = left_out
    for w in comp.provenance["warnings"]:        # the fit's, and how the unmeasured entries were completed
        print(f"warning: {args.recording}: {w}", file=sys.stderr)
    print(f"rod {rec.rod}: {len(fit.holds)} holds, {noise_text(fit.noise_mm)}")
    print(f"  {'load':>5} {'comp':>4} {'slope +- SE':>24} {'zero load +- SE (load / unload)':>36} {'sim um/N':>10}")
    for ln in fit.lines:
        z, se = ln.zero_load_kg, ln.zero_load_se_kg
        zeros = " / ".join(format_zero(z[k]).removesuffix(" g") + f" +- {1e3 * se[k]:.2g} g"
                           if np.isfinite(z[k]) and np.isfinite(se.get(k, np.nan)) else format_zero(z[k])
                           for k in ("load", "unload"))
        print(f"  {ln.axis.value:>5} {'xyz'[ln.component]:>4} "
              f"{format_pm(ln.slope_mm_per_N * 1e3, ln.se_mm_per_N * 1e3, 'um/N'):>24} {zeros:>36} "
              f"{sim.C_F[ln.component, ln.axis.index] * 1e3:10.3f}")
    print(f"  r_rod (Eq. 21) = {fit.r_rod:.4f}; c_rod (Eq. 23) = {comp.c_rod_um:.1f} um (simulated {sim.c_rod_um:.1f})")
    if (note := r_rod_note(fit.r_rod, str(sim.method))) is not None:
        print(f"  note: {note}")
    print("  r_mn (Eq. 20, measured / simulated per entry; - not measured):")
    for m, row in enumerate(comp.r_mn):
        print("    " + " ".join(f"{v:8.4f}" if np.isfinite(v) else f"{'-':>8}" for v in row) + f"   {'xyz'[m]}")
    guessed = [f"c{m + 1}{n + 1}" for m, n in STRUCTURAL_ENTRIES
               if comp.C_F_sigma is not None and not np.isfinite(comp.C_F_sigma[m, n])]
    if guessed:
        short = sorted({a.value for a in fit.holds.axis} - {ln.axis.value for ln in fit.lines})
        why = (f"the {', '.join(short)} series has too few holds at different loads to fit a line (3 or more "
               "needed)" if short else "the recording has no series that loads it")
        print(f"  not measured: {', '.join(guessed)} ({why}): the file holds r_rod x "
              "simulated there, with no uncertainty; `rodlab update` leaves it out")
    np.set_printoptions(precision=6, suppress=True)
    print(f"  measured C_F [mm/N] =\n{np.round(comp.C_F, 6) + 0.0}")     # no "-0." for what rounds to zero
    _print_load(fit)
    fig = png_file(args.png, "fig8.png")
    written = []
    if fig is not None:     # drawn first, then named by the file: a folder report shows it with this file only
        written.append(plot_fit(fit, fig, sim, title=f"rod {rec.rod}"))
        comp.provenance["figures"] = [os.path.relpath(written[-1], Path(args.output).parent)]
    written.insert(0, write_compliance(comp, args.output))
    for p in written:
        print(f"  wrote {p}")
    write_command_report(args, written, written[0].parent)
    return 0


def _print_load(fit) -> None:
    """With a load cell: the lines are against the measured force; nominal - measured per branch."""
    if fit.load is None:
        print("  load: mass_kg x g0 (no force_N column)")
        return
    ld = fit.load
    print(f"  load: force_N of the load cell (noise {ld.force_noise_N:.4f} N per reading); "
          f"mass_kg x g0 - force_N per branch (holds with a hanger on):")
    if ld.zero_offset_N:
        print(f"    load cell zero offset {ld.zero_offset_N:+.4f} N (its reading without a hanger), taken off before "
              "friction and tare; zero the load cell before the next recording (the compliance does not depend on it)")
    for b in ld.branches:
        sd = f"SD {b.sd_N:.4f} N, " if np.isfinite(b.sd_N) else ""
        print(f"    {b.axis.value:>3} {b.phase.value:<7} {b.diff_N:+8.4f} N ({sd}{b.n_holds} holds)")
    for axis in ld.friction_N:
        print(f"    {axis.value:>3} friction in the slides {ld.friction_N[axis]:+.4f} N, "
              f"tare {ld.tare_kg[axis] * 1e3:+.1f} g")
    h = fit.holds
    for axis in sorted(set(h.axis), key=lambda a: a.value):
        cells = " ".join(f"{k}:{v:+.3f}" for k, v, a in zip(h.step, ld.per_hold_N, h.axis) if a is axis)
        print(textwrap.fill(cells, 110, initial_indent=f"    {axis.value:>3} per hold (step:N) ",
                            subsequent_indent=" " * 8))


def parse_effects(specs: list[str]) -> dict:
    """``NAME[:key=value,...]`` -> {name: given parameters}, checked against the rig effect registry
    (:data:`rodlab.stiffness_rig.effects.RIG_EFFECTS`)."""
    return dict(parse_effect_specs(specs, rig_effect))


def rig_effects_help() -> str:
    return effects_help(RIG_EFFECTS)


def _places(sim, args) -> dict:
    """Where joint springs sit on the rod: from ``--design`` when given, else guessed from the tool vector."""
    design = None
    if getattr(args, "design", None):
        design = resolve_design(args.design)
    return joint_places(sim.tool_mm, design)


def cmd_simulate(args: argparse.Namespace) -> int:
    from rodlab.stiffness_rig.model import LoadSchedule, RigModel
    from rodlab.stiffness_rig.simulate import simulate_recording

    sim = compliance_arg(args.sim)
    effects = parse_effects(args.effect)
    design = _checked_design(args.design, explicit=True) if args.design else design_of_compliance(sim)
    if design is None and args.masses is None:
        print("note: the rod's design is unknown (not a built-in, no design file in the compliance file's "
              "provenance): the paper's masses up to 2 kg; on a carbon rod give --design or --masses 0.5,1,1.5 "
              "(its 15 N linear range)", file=sys.stderr)
    try:
        masses = default_masses(design) if args.masses is None else tuple(float(m) for m in args.masses.split(","))
        axes = tuple(a.strip() for a in args.axes.split(","))
        for a in axes:
            LoadAxis.parse(a, "load axis")
    except ValueError as e:
        raise RodlabError(f"--masses / --axes: {e}") from e
    proto = LoadSchedule(axes=axes, masses=masses, repeats=args.repeats, hold_s=args.hold_s, rate_Hz=args.rate_hz)
    _warn_linear_range(proto, design)
    model = RigModel(sim.C_F, effects, noise_mm=args.noise_um * 1e-3, seed=args.seed, places=_places(sim, args),
                     load_cell_noise_N=args.load_cell_noise_n)
    stated = {str(e): p for e, p in model.effects.items()}
    path = simulate_recording(model, proto, args.output, rod=sim.rod,
                              extra_meta={"effects": json.dumps(stated) if stated else "none", "seed": args.seed,
                                          "sim": f"{args.sim} ({sim.method}"
                                                 + (f", {sim.provenance['model']})" if sim.provenance.get("model")
                                                    else ")")})
    print(f"wrote {path}: {len(proto.holds())} holds (masses {', '.join(f'{m:g}' for m in masses)} kg) on rod "
          f"{sim.rod}, effects: {stated or 'none'}")
    return 0


def _checked_design(design_spec: str, explicit: bool):
    """The rod's design to check a load plan against: the one given (errors raised), else the plan's or the
    compliance file's rod when it is a built-in name (another rod: None, nothing to check against)."""
    try:
        return resolve_design(design_spec)
    except RodlabError:
        if explicit:
            raise
        return None


def _warn_linear_range(schedule, design) -> None:
    """Warn (stderr) about every mass beyond a carbon rod's linear range, naming its holds (no design: nothing
    to check against)."""
    for w in linear_range_warnings(schedule, design) if design is not None else []:
        print(f"warning: {w}", file=sys.stderr)


def cmd_acquire(args: argparse.Namespace) -> int:
    from rodlab.stiffness_rig.acquire import RecordingLock, acquire
    from rodlab.stiffness_rig.config import read_plan, read_profile
    from rodlab.stiffness_rig.resume import next_free_name, resume_point
    profile, plan = read_profile(args.profile), read_plan(args.plan)
    _warn_linear_range(plan.schedule, _checked_design(args.design or plan.rod, explicit=args.design is not None))
    output = args.output
    if args.new_file and os.path.exists(output) and os.path.getsize(output) > 0:
        output = str(next_free_name(output))
        print(f"{args.output} exists; recording into {output}")
    if not args.non_interactive and not (sys.stdin and sys.stdin.isatty()):   # before any file is made
        raise RodlabError("no terminal to prompt the operator to hang the weights; use --non-interactive with a "
                          "[loader] in the profile, or run in a terminal")
    start = resume_point(output, profile, plan)              # refuses another plan, rate or device up front
    if start.complete:
        print(f"{output} already holds all {start.holds_total} holds of this plan; nothing to record")
        return 0
    if start.resuming:
        RecordingLock(Path(output)).release()      # another acquisition at work is named before "resuming" is said
        print(f"resuming after hold {start.holds_done}/{start.holds_total} (plan {plan.path}, {output})")

    def operator(prompt: str) -> None:
        if not sys.stdin or not sys.stdin.isatty():
            raise RodlabError("no terminal to prompt the operator; use --non-interactive with a [loader]")
        input(f"\n{prompt} ")

    bar = bar_of(total=None, desc="rig acquisition", unit="hold")
    last = []

    def progress(st) -> None:                      # tqdm's estimate of the plan's remaining time from its rate
        last[:] = [st]
        if bar.total != st.holds_total:
            bar.total = st.holds_total
        bar.update(st.holds_done - bar.n)
        bar.set_postfix_str(f"{st.label}; {st.samples} samples, {st.garbage} garbage lines, {st.reconnects} "
                            f"reconnects")
    try:
        with bar:
            out = acquire(profile, plan, output, operator=None if args.non_interactive else operator,
                          progress=progress, use_loader=args.non_interactive)
    except KeyboardInterrupt:
        print(f"\ninterrupted: every sample so far is in {output}; re-run the same command (-o {output}) to resume")
        return 130
    print(f"\nwrote {out}")
    if last and (last[0].garbage or last[0].reconnects):    # counted while recording: said once at the end
        print(f"  the instruments sent {last[0].garbage} garbage line(s) (skipped) and the ports were reconnected "
              f"{last[0].reconnects} time(s) in this run; `-v` shows each")
    if last and last[0].timeouts:
        print(f"  {last[0].timeouts} request(s) went unanswered and were repeated: each such sample came one port "
              f"timeout later (its time is the answer's, so the fit is unaffected); many of them point at the cable, "
              f"the baud rate or a timeout_s shorter than the instrument's answer")
    return 0


def cmd_simulator(args: argparse.Namespace) -> int:
    from rodlab.stiffness_rig.model import RigModel
    from rodlab.stiffness_rig.simdevice import Faults, SimulatedRig

    sim = compliance_arg(args.sim)
    if args.profile is None and args.link is None:
        raise RodlabError("give --link (the one-port simulated counter) or --profile with --link-dir")
    effects = parse_effects(args.effect)
    loop = effects.get("load_hysteresis") or {}
    if loop.get("eta_loop") and not loop.get("top_kg"):
        raise RodlabError("--effect load_hysteresis: eta_loop needs top_kg (the loop's top load [kg]) in the live "
                          "simulator, which does not know the acquisition's plan: add top_kg=<the plan's largest mass>")
    if args.profile is not None:
        model = RigModel(sim.C_F, effects, places=_places(sim, args), load_cell_noise_N=args.load_cell_noise_n)
        devices, what = profile_simulators(args, model, Faults(garbage=args.garbage))
    else:
        model = RigModel(sim.C_F, effects, places=_places(sim, args))
        devices = [SimulatedRig(model, Path(args.link), protocol=args.protocol, checksum=args.checksum,
                                faults=Faults(garbage=args.garbage))]
        what = f"on {args.link} ({args.protocol}, 3 gauges in um + temperature"
    # kill / hang-up end the simulator as Ctrl-C does: its links removed
    with kill_as_interrupt(), contextlib.ExitStack() as stack:
        for dev in devices:
            stack.enter_context(dev)
        print(f"simulated rig of rod {sim.rod} {what}; loader: 'LOAD <axis> <phase> <mass_kg>'); Ctrl-C to stop",
              flush=True)
        t0 = time.monotonic()
        try:
            while not args.seconds or time.monotonic() - t0 < args.seconds:
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
    return 0
