"""The fit chart of haptic-tune identify (--chart): per axis, the measured velocity against
the identified model's free run under the logged force, and their difference.

  identify-fit: "axes": [{"axis", "estimate": {"mass_kg", "damping_n_s_per_m", "coulomb_n",
                          "offset_n"}, "delay_s", "measured_velocity", "predicted_velocity",
                          "velocity_error" (each {"t_s": [...], "value": [...]}),
                          "velocity_rms_error_mps", "explained_fraction"}]
"""


def draw_fit(plt, np, chart, figure):
    axes = chart["axes"]
    if not axes:
        raise ValueError("no axes to draw")
    panels = figure.subplots(len(axes), 1, sharex=True, squeeze=False)[:, 0]
    for ax, entry in zip(panels, axes):
        estimate = entry["estimate"]
        measured = entry["measured_velocity"]
        predicted = entry["predicted_velocity"]
        error = entry["velocity_error"]
        ax.plot(measured["t_s"], measured["value"], color="black", linewidth=0.8,
                label=f"measured v{entry['axis']} (backward difference of x{entry['axis']})")
        ax.plot(predicted["t_s"], predicted["value"], color="tab:red", linewidth=0.8,
                alpha=0.85,
                label=f"model: m = {estimate['mass_kg']:.4g} kg, "
                      f"b = {estimate['damping_n_s_per_m']:.4g} N s/m, "
                      f"F_c = {estimate['coulomb_n']:.3g} N, F_0 = {estimate['offset_n']:.3g} N")
        ax.plot(error["t_s"], error["value"], color="tab:blue", linewidth=0.6, alpha=0.7,
                label=f"model \u2212 measured: RMS {1e3 * entry['velocity_rms_error_mps']:.3g} "
                      f"mm/s, explains {100 * entry['explained_fraction']:.2f} % of the variance")
        ax.set_ylabel(f"velocity v{entry['axis']} (m/s)")
        ax.grid(True, alpha=0.35)
    panels[-1].set_xlabel("time t (s)")
    return list(panels)


DRAW = {"identify-fit": draw_fit}
