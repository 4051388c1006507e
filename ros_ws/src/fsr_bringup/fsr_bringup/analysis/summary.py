"""Markdown summaries of :func:`fsr_bringup.analysis.metrics.flight_metrics`: one run (quantity, value) or
several side by side (quantity, one column per run)."""

from __future__ import annotations

from typing import Any

from fsr_sim.contract import ATTITUDE_CMD, ODOM, ODOM_TRUTH, SIM_STATUS, WRENCH_SHORTFALL, SimStatus

CHANNEL_LABELS = {"fx": "f_x", "fy": "f_y", "fz": "f_z", "tx": "tau_x", "ty": "tau_y", "tz": "tau_z"}


def _num(value: Any, digits: int = 3) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        tiny_or_huge = abs(value) >= 1e4 or (value != 0 and abs(value) < 1e-3)
        return f"{value:.{digits}g}" if tiny_or_huge else f"{value:.{digits}f}"
    return str(value)


def _vector(values: list | None, digits: int = 3) -> str:
    return "n/a" if values is None else "[" + ", ".join(_num(v, digits) for v in values) + "]"


def _channels(values: dict | None, digits: int = 3) -> str:
    """``f_x 0.264, f_y ...`` for the channels with a value (a zero truth has no settling time)."""
    if not values:
        return "n/a"
    shown = [f"{CHANNEL_LABELS.get(k, k)} {_num(v, digits)}" for k, v in values.items() if v is not None]
    return ", ".join(shown) or "n/a"


def _measured_on(tracking: dict[str, Any]) -> str:
    """What the tracking errors are taken on: the true state (``odom`` itself, or ``odom_truth`` beside a measured
    ``odom``), or - a measured ``odom`` without ``odom_truth`` recorded - the measurement."""
    on = tracking.get("measured_on", ODOM.name)
    if on == ODOM_TRUTH.name:
        return f"true state (`{ODOM_TRUTH.name}`; `{ODOM.name}` is the noisy measurement)"
    if tracking.get("odom_is_true_state", True):
        return f"true state (`{ODOM.name}`: no sensor stage)"
    return f"**measured `{ODOM.name}`** (sensor stage on, `{ODOM_TRUTH.name}` not recorded)"


def summary_rows(metrics: dict[str, Any]) -> list[tuple[str, str]]:
    """(quantity, value) rows of one run's metrics, in a fixed order."""
    rows: list[tuple[str, str]] = []
    status = SimStatus.from_dict(metrics.get(SIM_STATUS.name))
    end = f"{status.state} ({status.reason})" if status else "n/a"
    if metrics.get("interrupted_at_s") is not None and status:
        end = f"**interrupted at t = {metrics['interrupted_at_s']:.3f} s** ({status.reason})"
    rows.append(("end state", end + (" - **truncated recording**" if metrics.get("truncated") else "")))
    rows.append(("duration [s] / steps", f"{_num(metrics.get('duration_s'))} / {_num(metrics.get('steps'))}"))
    if status and status.failsafe_steps:  # the controller missed steps (killed, hung, link down)
        rows.append(("lockstep failsafe", f"**{status.failsafe_steps} steps** on the failsafe in "
                                          f"{status.incidents} incident(s), "
                                          f"{status.late_commands} late command(s) ignored"))
    weights = metrics.get("masses")
    if weights:
        text = (f"plant (true) {_num(weights['plant_kg'])}, controller's model {_num(weights['controller_model_kg'])} "
                f"({weights['vehicle']})")
        if weights["estimator_model_kg"] is not None:
            text += f", estimator's model {_num(weights['estimator_model_kg'])}"
        rows.append(("masses [kg]", text))
    tracking = metrics.get("tracking")
    if tracking:
        commanded = tracking.get("attitude_vs") == ATTITUDE_CMD.name
        against = "R_c, commanded" if commanded else "R_d, planner"
        rows.append(("tracking errors measured on", _measured_on(tracking)))
        for key, label in (
            ("position_error_m", "position error [m]"),
            ("attitude_error_deg", f"attitude error vs {against} [deg]"),
            ("attitude_vs_reference_deg", "attitude vs planner R_d [deg]"),
            ("velocity_error_m_s", "velocity error [m/s]"),
        ):
            item = tracking.get(key)
            if item is None or (key == "attitude_vs_reference_deg" and not commanded):
                continue
            rows.append((
                f"{label} final / peak (at t) / RMS",
                f"{_num(item['final'])} / {_num(item['peak'])} (at {_num(item['peak_time_s'], 2)} s) / "
                f"{_num(item['rms'])}",
            ))
    odometry = metrics.get("odometry_error")
    if odometry:
        rows.append(("odom (measured) vs true state: position [m] / attitude [deg] RMS",
                     f"{_num(odometry['position_m']['rms'])} / {_num(odometry['attitude_deg']['rms'])} "
                     "(what the controller was fed, not the tracking error)"))
    thrust = metrics.get("commanded_thrust_N")
    if thrust:
        rows.append(("commanded thrust [N] final / peak", f"{_num(thrust['final'])} / {_num(thrust['peak'])}"))
    saturation = metrics.get("saturation")
    if saturation:
        speed = saturation["rotor_speed"]
        text = f"{speed['steps']} steps"
        if speed["steps"]:
            text += f", first at {_num(speed['first_time_s'], 3)} s, worst rotor {speed['worst_rotor']}"
        rows.append(("rotor speed saturation", text))
        if saturation.get("tilt"):
            rows.append(("tilt saturation", f"{saturation['tilt']['steps']} steps"))
    plan = metrics.get("plan")
    if plan:
        text = f"{plan['kind']}, at rest from {_num(plan['end_s'])} s"
        if plan.get("ended_mid_path"):
            text += f" - **the flight ended mid-path at {_num(metrics.get('end_time_s'))} s**"
        rows.append(("plan (trajectory.kind)", text))
    adjustments = metrics.get("plan_adjustments")
    if adjustments:
        rows.append(("legs and paths beyond the authority", "; ".join(item["text"] for item in adjustments)))
    path = metrics.get("path")
    if path:
        flown = f"flown ({path['flown_from']})"
        for key, label in (("speed_m_s", "speed [m/s]"), ("acceleration_m_s2", "acceleration [m/s^2]")):
            planned, flight = path["planned"][key], path["flown"][key]
            rows.append((f"{label} peak / RMS", f"planned {_num(planned['peak'])} / {_num(planned['rms'])}; "
                                                f"{flown} {_num(flight['peak'])} / {_num(flight['rms'])}"))
        rows.append(("path length [m]", f"planned {_num(path['planned']['length_m'])}; "
                                        f"{flown} {_num(path['flown']['length_m'])}"))
    compensation = metrics.get("compensation")
    if compensation:
        text = compensation["mode"]
        if compensation["mode"] == "estimate":
            text = (f"estimate (controller's own observer, c0 = {_num(compensation['c0'])}, r = {compensation['r']}); "
                    f"late estimates {compensation['late_estimates']}; off in contact: "
                    f"{_num(compensation['contact_steps'])} states")
        rows.append(("disturbance compensation", text))
    shortfall = metrics.get(WRENCH_SHORTFALL.name)
    if shortfall:
        gave_way = [
            f"{axis} {item['steps']} steps (max {_num(item['max_shortfall'])} at {_num(item['max_time_s'], 2)} s)"
            for axis, item in shortfall.items() if isinstance(item, dict) and item["steps"]
        ]
        rows.append(("gave way at the rotor limits [N, N m]", ", ".join(gave_way) or "no axis"))
    wrench = metrics.get("external_wrench")
    if wrench:
        frame = wrench.get("frame", "body FRD")
        rows.append((f"wrench estimate, mean last 1 s ({frame})", _vector(wrench["estimate_mean_last_s"])))
        if wrench.get("effective_truth_mean_last_s") is not None:
            rows.append(("effective truth, mean last 1 s", _vector(wrench["effective_truth_mean_last_s"])))
        rows.append(("external wrench only, mean last 1 s", _vector(wrench["truth_mean_last_s"])))
        if wrench.get("settling_time_s") is not None:
            rows.append((f"settling time [s] ({wrench['settling']}, 3 % band)", _channels(wrench["settling_time_s"])))
            rows.append(("MAE over the flight [N, N m]", _channels(wrench["mae"], 4)))
            rows.append(("max error after T [N, N m]",
                         f"T = {_num(wrench['after_s'], 2)} s: {_channels(wrench['max_error_after'], 3)}"))
            rows.append(("RMS error vs effective truth after t_s",
                         f"t_s = {_num(wrench['rms_from_s'], 2)} s: {_vector(wrench['rms_error'])}"))
        rows.append(("RMS error vs external wrench only after t_s",
                     f"t_s = {_num(wrench['rms_from_s'], 2)} s: {_vector(wrench['rms_error_vs_external'])}"))
    mass = metrics.get("mass")
    if mass:
        rows.append(("mass estimate final / true [kg]", f"{_num(mass['estimate_final_kg'])} / {_num(mass['true_kg'])}"))
    ratio = metrics.get("thrust_ratio")
    if ratio:
        text = f"{_vector(ratio['ground'], 4)} / {_vector(ratio['ceiling'], 4)}"
        rows.append(("ground / ceiling thrust ratio T/T_OGE range", text))
        for name, cap in (ratio.get("at_cap") or {}).items():
            if cap["steps"]:
                rows.append((f"{name} effect at its cap {_num(cap['max_ratio'], 2)} (outside the model)",
                             f"**{cap['steps']} states**, first at {_num(cap['first_time_s'], 3)} s"))
    figures = metrics.get("figures")
    if figures:
        rows.append(("figures", ", ".join(figures)))
    return rows


def _notes(notes: list[str]) -> list[str]:
    return ["", "Notes:", *(f"- {note}" for note in notes)] if notes else []


def diagnosis_lines(found: dict[str, Any] | None) -> list[str]:
    """The *Diagnosis* section of a flight that diverged or saturated much (empty otherwise)."""
    if not found:
        return []
    lines = ["", f"**Diagnosis** ({found['why']}):", ""]
    first = found.get("first_saturation")
    if first is None:
        lines.append("- no rotor reached a limit")
    elif first.get("axis") is not None:
        lines.append(f"- first saturated step: {first['step']} (t = {_num(first['time_s'])} s), the "
                     f"{first['axis']} demand gave way by {_num(first['shortfall'])}")
    else:
        lines.append(f"- first rotor command at a limit: t = {_num(first['time_s'])} s (rotor {first.get('rotor')})")
    if found.get("rotor_limit_share") is not None:
        lines.append(f"- steps with a rotor at a speed limit: {found['rotor_limit_share']:.1%}"
                     + (f"; tilts at their limit: {found['tilt_limit_share']:.1%}"
                        if found.get("tilt_limit_share") is not None else ""))
    causes = found.get("likely_causes") or []
    for item in causes:
        lines.append(f"- likely cause: {item['cause']} - change `{item['key']}`")
    if not causes:
        lines.append("- likely cause: none fsr can name from the scenario (see the saturation and gave-way rows)")
    return lines


def markdown_summary(metrics: dict[str, Any]) -> str:
    """A title line (scenario, recording), a two-column Markdown table (quantity, value), the diagnosis of a
    flight that diverged or saturated much, and the notes."""
    where = f" ({metrics['namespace']})" if metrics.get("namespace") not in (None, "/") else ""
    lines = [
        f"### Flight `{metrics.get('scenario')}`{where}",
        "",
        f"Recording: `{metrics.get('recording')}`",
        "",
        "| quantity | value |",
        "|---|---|",
        *(f"| {name} | {value} |" for name, value in summary_rows(metrics)),
    ]
    return "\n".join(lines + diagnosis_lines(metrics.get("diagnosis")) + _notes(metrics.get("notes") or [])) + "\n"


def comparison_summary(labels: list[str], runs: list[dict[str, Any]], notes: list[str] | None = None) -> str:
    """One table, a column per run (``labels``); a quantity missing in a run reads ``n/a``."""
    tables = [dict(summary_rows(metrics)) for metrics in runs]
    order: list[str] = []
    for metrics in runs:
        order += [name for name, _ in summary_rows(metrics) if name not in order and name != "figures"]
    lines = [
        "### Flights " + ", ".join(f"`{label}`" for label in labels),
        "",
        *(f"- `{label}`: scenario `{m.get('scenario')}`, recording `{m.get('recording')}`"
          for label, m in zip(labels, runs, strict=True)),
        "",
        "| quantity | " + " | ".join(labels) + " |",
        "|---|" + "---|" * len(labels),
        *(f"| {name} | " + " | ".join(table.get(name, "n/a") for table in tables) + " |" for name in order),
    ]
    all_notes = list(notes or []) + [f"{label}: {note}" for label, m in zip(labels, runs, strict=True)
                                     for note in m.get("notes") or []]
    return "\n".join(lines + _notes(all_notes)) + "\n"
