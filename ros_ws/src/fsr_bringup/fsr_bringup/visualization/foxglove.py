"""The Foxglove layout shipped with fsr (``docs/foxglove/fsr.json``), generated from the flight contract.

    python -m fsr_bringup.visualization.foxglove > docs/foxglove/fsr.json

A 3D panel in ``map`` (ENU: the vehicle upright; ``/tf``, ``/tf_static`` and ``markers`` of a recording) beside
three plots against the messages' header stamps (simulated time): the position and its reference per axis,
the estimated external force against the true one (``wrench_truth``: without a model mismatch the estimator's
effective truth), and the rotor speeds: commanded (``rotor_cmd``) and, where the rotors lag their commands,
what they did (``rotor_state``, the same colour; empty without actuator dynamics). Topics are the root namespace's
(a fleet's vehicles: edit the paths).
"""

from __future__ import annotations

import json

from fsr_sim import contract

AXES = ("x", "y", "z")
COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f")
ROTORS_PLOTTED = 8  # rotor_cmd velocities plotted (a path past a quadrotor's four simply stays empty)


def _series(path: str, label: str, colour: str, dashed: bool = False) -> dict:
    series = {"value": path, "label": label, "color": colour, "enabled": True, "timestampMethod": "headerStamp"}
    return {**series, "lineStyle": "dashed"} if dashed else series


def _plot(title: str, series: list[dict]) -> dict:
    return {"title": title, "paths": series, "showXAxisLabels": True, "showYAxisLabels": True, "showLegend": True,
            "legendDisplay": "top", "showPlotValuesInLegend": False, "isSynced": True, "xAxisVal": "timestamp",
            "sidebarDimension": 200}


def layout() -> dict:
    """The layout document (Foxglove's JSON layout format)."""
    odom, reference, truth, estimate, rotors, actual, markers = (contract.resolve(topic.name) for topic in (
        contract.ODOM, contract.REFERENCE, contract.WRENCH_TRUTH, contract.WRENCH_ESTIMATE, contract.ROTOR_CMD,
        contract.ROTOR_STATE, contract.MARKERS))
    position = [_series(f"{odom}.pose.pose.position.{a}", f"p_{a}", COLOURS[i]) for i, a in enumerate(AXES)]
    position += [_series(f"{reference}.points[0].transforms[0].translation.{a}", f"p_{a},d", COLOURS[3 + i])
                 for i, a in enumerate(AXES)]
    force = [_series(f"{estimate}.wrench.force.{a}", f"f_e,{a} estimate", COLOURS[i]) for i, a in enumerate(AXES)]
    force += [_series(f"{truth}.wrench.force.{a}", f"f_e,{a} true", COLOURS[3 + i]) for i, a in enumerate(AXES)]
    speeds = [_series(f"{rotors}.velocity[{i}]", f"w_{i + 1}", COLOURS[i]) for i in range(ROTORS_PLOTTED)]
    speeds += [_series(f"{actual}.velocity[{i}]", f"w_{i + 1} measured", COLOURS[i], dashed=True)
               for i in range(ROTORS_PLOTTED)]
    scene = {
        "cameraState": {"perspective": True, "distance": 8, "phi": 60, "thetaOffset": 45, "target": [0, 0, 0],
                        "targetOffset": [0, 0, 0], "targetOrientation": [0, 0, 0, 1], "fovy": 45, "near": 0.05,
                        "far": 5000},
        "followMode": "follow-position", "followTf": contract.MAP_FRAME,
        "scene": {"transforms": {"showLabel": True, "axisScale": 0.3}},
        "transforms": {f"frame:{contract.BODY_FRAME}": {"visible": True}},
        "topics": {markers: {"visible": True}, contract.TF.name: {"visible": True}},
        "layers": {"grid": {"layerId": "foxglove.Grid", "frameId": contract.MAP_FRAME, "visible": True, "size": 20,
                            "divisions": 20, "lineWidth": 1, "color": "#248eff", "position": [0, 0, 0],
                            "rotation": [0, 0, 0], "order": 1}},
        "publish": {"type": "point"},
    }
    config = {"3D!fsr": scene,
              "Plot!position": _plot(f"position and reference [m] ({contract.WORLD_FRAME})", position),
              "Plot!force": _plot(f"external force [N] ({contract.BODY_FRAME}): estimate and truth", force),
              "Plot!rotors": _plot("rotor speeds [rad/s]: commanded, measured", speeds)}
    plots = {"direction": "column", "first": "Plot!position",
             "second": {"direction": "column", "first": "Plot!force", "second": "Plot!rotors", "splitPercentage": 50},
             "splitPercentage": 33}
    return {"configById": config, "globalVariables": {}, "userNodes": {}, "playbackConfig": {"speed": 1},
            "layout": {"direction": "row", "first": "3D!fsr", "second": plots, "splitPercentage": 55}}


def layout_text() -> str:
    """The layout as the file holds it."""
    return json.dumps(layout(), indent=2) + "\n"


if __name__ == "__main__":
    print(layout_text(), end="")
