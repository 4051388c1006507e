"""A short Markdown summary of :func:`fsr_bringup.analysis.metrics.flight_metrics` for a report."""

from __future__ import annotations

from typing import Any


def _num(value: Any, digits: int = 3) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        tiny_or_huge = abs(value) >= 1e4 or (value != 0 and abs(value) < 1e-3)
        return f"{value:.{digits}g}" if tiny_or_huge else f"{value:.{digits}f}"
    return str(value)


def _vector(values: list | None, digits: int = 3) -> str:
    return "n/a" if values is None else "[" + ", ".join(_num(v, digits) for v in values) + "]"


def markdown_summary(metrics: dict[str, Any]) -> str:
    """A title line, a two-column Markdown table (quantity, value) and the notes as a list."""
    rows: list[tuple[str, str]] = []
    status = metrics.get("sim_status")
    end = f"{status.get('state')} ({status.get('reason')})" if status else "n/a"
    if metrics.get("interrupted_at_s") is not None:
        end = f"**interrupted at t = {metrics['interrupted_at_s']:.3f} s** ({status.get('reason')})"
    rows.append(("end state", end + (" - **truncated recording**" if metrics.get("truncated") else "")))
    rows.append(("duration [s] / steps", f"{_num(metrics.get('duration_s'))} / {_num(metrics.get('steps'))}"))
    tracking = metrics.get("tracking")
    if tracking:
        for key, label in (
            ("position_error_m", "position error [m]"),
            ("attitude_error_deg", "attitude error [deg]"),
            ("velocity_error_m_s", "velocity error [m/s]"),
        ):
            item = tracking[key]
            rows.append((
                f"{label} final / peak (at t) / RMS",
                f"{_num(item['final'])} / {_num(item['peak'])} (at {_num(item['peak_time_s'], 2)} s) / "
                f"{_num(item['rms'])}",
            ))
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
    shortfall = metrics.get("wrench_shortfall")
    if shortfall:
        gave_way = [
            f"{axis} {item['steps']} steps (max {_num(item['max_shortfall'])} at {_num(item['max_time_s'], 2)} s)"
            for axis, item in shortfall.items() if isinstance(item, dict) and item["steps"]
        ]
        rows.append(("gave way at the rotor limits [N, N m]", ", ".join(gave_way) or "no axis"))
    wrench = metrics.get("external_wrench")
    if wrench:
        rows.append(("external wrench estimate, mean last 1 s", _vector(wrench["estimate_mean_last_s"])))
        rows.append(("external wrench truth, mean last 1 s", _vector(wrench["truth_mean_last_s"])))
        rows.append((f"estimate RMS error after {_num(wrench['rms_from_s'], 2)} s", _vector(wrench["rms_error"])))
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
    where = f" ({metrics['namespace']})" if metrics.get("namespace") not in (None, "/") else ""
    lines = [
        f"### Flight `{metrics.get('scenario')}`{where}",
        "",
        "| quantity | value |",
        "|---|---|",
        *(f"| {name} | {value} |" for name, value in rows),
    ]
    notes = metrics.get("notes") or []
    if notes:
        lines += ["", "Notes:", *(f"- {note}" for note in notes)]
    return "\n".join(lines) + "\n"
