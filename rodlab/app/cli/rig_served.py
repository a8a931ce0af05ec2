"""``rodlab rig simulator --profile``: every instrument of a rig profile served on its own pseudo-terminal, and
the profile pointed at them (``sim.profile.toml``: its ports replaced, parity N, a loader added where it has none)."""
from __future__ import annotations

import re
from pathlib import Path

from rodlab.stiffness_rig.drivers import DRIVERS

from ...core.errors import RodlabError
from ...core.fileio import atomic_write_text

__all__ = ["profile_simulators"]


def _served_loader(profile) -> str:
    """A ``[loader]`` for the served profile when it has none: the simulated rig's loader answers on every text
    instrument's port, so ``rig acquire --non-interactive`` runs on the served profile as it is."""
    if profile.loader_instrument is not None:
        return ""
    text = [i.name for i in profile.instruments if DRIVERS[i.protocol].text_lines]
    if not text:
        return ""
    return ("\n# added by `rodlab rig simulator`: the simulated rig's loader answers on this instrument's port\n"
            f'[loader]\ninstrument = "{text[0]}"\ncommand = "LOAD {{axis}} {{phase}} {{mass_kg:.4f}}\\r\\n"\n')


def profile_simulators(args, model, faults):
    """The simulators of every instrument of ``--profile`` under ``--link-dir``, and ``sim.profile.toml``
    there: the profile with each instrument's port pointed at its simulator."""
    from rodlab.stiffness_rig.config import read_profile
    from rodlab.stiffness_rig.siminstruments import SimBench, simulators_for

    profile = read_profile(args.profile)
    if not hasattr(profile, "instruments"):
        raise RodlabError(f"{args.profile}: --profile takes a rodlab.rigprofile/2 profile; serve a /1 profile's "
                          f"counter with --link")
    if args.link_dir is None:
        raise RodlabError("--profile needs --link-dir (where the instruments' pty links go)")
    folder = Path(args.link_dir)
    folder.mkdir(parents=True, exist_ok=True)
    links = {ins.name: folder / ins.name for ins in profile.instruments}
    ports = iter(str(links[ins.name]) for ins in profile.instruments)
    text = re.sub(r"""(?m)^(\s*port\s*=\s*)(".*?"|'.*?')""", lambda m: f'{m.group(1)}"{next(ports)}"',
                  Path(args.profile).read_text(encoding="utf-8"))
    # a pty has no parity bits: Linux drops PARENB and glibc then refuses the settings (EINVAL)
    text = re.sub(r"""(?m)^(\s*parity\s*=\s*)(".*?"|'.*?')(.*)$""",
                  lambda m: f'{m.group(1)}"N"{m.group(3)}  # served on a pseudo-terminal, which has no parity bits',
                  text)
    text += _served_loader(profile)
    written = atomic_write_text(folder / "sim.profile.toml", text)
    sims = simulators_for(profile, SimBench(model), links, faults)
    names = ", ".join(f"{i.name} ({i.protocol})" for i in profile.instruments)
    return sims, f"as {names} under {folder}; profile {written}"
