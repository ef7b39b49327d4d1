"""The couplings each stability model sizes (haptic-tune size --json): the predictions the
maps put beside the measured verdicts. Each is the stiffest k_c the model accepts for the
coupling damping b_c, on its own terms (docs/stability-models.md):

  paper    (21) with the hold (13) as printed             every passive operator (it claims)
  encoder  (21) with the exact ZOH and backward difference every passive operator (it claims)
  passive  the port condition, delay-aware                 every passive operator: a proof
  exact    the sampled-data loop, sized on the proof       every passive operator
  class    exact model, operators of pen-grip.toml         the declared class only
  scene    the port condition against the scene's wall     every passive operator, this wall
"""

import dataclasses

from hil import number


@dataclasses.dataclass(frozen=True)
class Design:
    name: str
    label: str
    holds_for: str
    options: tuple  # haptic-tune size's options beyond the device


def designs(ctx, scene_path):
    grip = str(ctx.source_dir / "config/operators/pen-grip.toml")
    return [
        Design("paper", "paper: (21) with (13) as printed", "every passive operator (claimed)",
               ("--model", "paper", "--no-exact-check")),
        Design("encoder", "encoder: (21) with the exact ZOH", "every passive operator (claimed)",
               ("--model", "encoder", "--no-exact-check")),
        Design("passive", "passive: the port condition (a proof)", "every passive operator",
               ()),
        Design("exact", "exact: the sampled-data loop", "every passive operator",
               ("--model", "exact")),
        Design("class", "class: exact model, pen-grip operators", "the pen-grip class",
               ("--model", "exact", "--operator-class", grip)),
        Design("scene", "scene: the port condition against this wall",
               "every passive operator, this wall", ("--scene", str(scene_path))),
    ]


def sized_stiffness(ctx, device, design, coupling_damping_n_s_per_m):
    """k_c (N/m) the design's model sizes for the device at b_c."""
    return size(ctx, device, design, coupling_damping_n_s_per_m)["stiffness"]


def size(ctx, device, design, coupling_damping_n_s_per_m):
    """haptic-tune size's whole answer. Its exit 1 (the exact model's cross-check refused the
    answer) is an answer too: the JSON says why (exact_check)."""
    args = [ctx.program("haptic-tune"), "size", "--mass", number(device.mass_kg), "--damping",
            number(device.damping_n_s_per_m), "--rate", number(device.rate_hz),
            "--coupling-damping", number(coupling_damping_n_s_per_m), "--json", *design.options]
    if device.delay_s > 0:
        args += ["--delay", number(device.delay_s)]
    return ctx.run_json(args, f"haptic-tune size ({design.name})", exits=(0, 1))
