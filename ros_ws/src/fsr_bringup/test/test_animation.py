"""fsr-analyze --animate: the video has the frames its duration, fps and speed ask for, each frame shows the
vehicle where the recording has it, the geometry is the plant's, bad options are one line, an interruption
leaves no file."""

from __future__ import annotations

from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image

from fsr_bringup.analysis.animation import CENTRE_COLOUR, FlightAnimation, gif_durations_ms, write_animation
from fsr_bringup.analysis.animation_scene import NED_TO_VIEW, build_scene, view_of
from fsr_bringup.analysis.figure_options import AnimationOptions
from fsr_bringup.analysis.load import load_flight
from fsr_bringup.cli.analyze_cli import main as analyze_main
from fsr_sim.model.rotors import rotor_axes
from fsr_sim.recording.reader import open_recording

SYNTHETIC_S = 2.0  # the synthetic flight's duration (fixtures: 2 s at 1 kHz)


def synthetic_position_ned(t: float) -> np.ndarray:
    """The synthetic flight's odometry position (test/conftest.py: the reference plus position_error_x)."""
    error_x = 0.5 * t if t <= 1.0 else 0.5 - 0.2 * (t - 1.0)
    return np.array([t + error_x, 0.0, -1.0 - 0.5 * t])


def decoded_frames(path: Path) -> tuple[dict, list[np.ndarray]]:
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    return meta, [np.frombuffer(frame, np.uint8).reshape(height, width, 3) for frame in reader]


def marker_centroid(frame: np.ndarray, animation: FlightAnimation, tolerance: float) -> np.ndarray:
    """(column, row) [px] of the centre of the pixels within ``tolerance`` of the centre marker's colour, the
    legend's marker left out."""
    target = np.array([int(CENTRE_COLOUR[i:i + 2], 16) for i in (1, 3, 5)], dtype=float)
    rows, columns = np.nonzero(np.linalg.norm(frame[..., :3].astype(float) - target, axis=-1) <= tolerance)
    legend = animation.figure.legends[0].get_window_extent()
    up = animation.size[1] - rows
    outside = ~((columns >= legend.x0) & (columns <= legend.x1) & (up >= legend.y0) & (up <= legend.y1))
    assert np.count_nonzero(outside) >= 20, "the centre marker's colour is not in the frame"
    return np.array([columns[outside].mean() + 0.5, rows[outside].mean() + 0.5])  # pixel centres


def run_cli(argv: list[str]) -> int:
    try:
        return analyze_main(argv)
    except SystemExit as exit_info:  # argparse's errors
        return int(exit_info.code)


@pytest.fixture(scope="module")
def animated(synthetic_recording: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The synthetic flight animated at 10 fps, at real time and twice as fast (the CLI, metrics only)."""
    out = {}
    for name, extra in (("real_time", []), ("double", ["--speed", "2"])):
        folder = tmp_path_factory.mktemp(name)
        assert run_cli([str(synthetic_recording), "--out", str(folder), "--no-figures", "--animate", "--fps", "10",
                        *extra]) == 0
        out[name] = folder / "animation.mp4"
    return out


def test_the_mp4_has_duration_times_fps_frames_and_speed_2_half_as_many(animated: dict[str, Path]) -> None:
    meta, frames = decoded_frames(animated["real_time"])
    assert meta["fps"] == 10 and meta["size"] == AnimationOptions().size and meta["codec"] == "h264"
    assert abs(len(frames) - SYNTHETIC_S * 10) <= 1  # 21: t = 0, 0.1, ..., 2.0 s
    _, double = decoded_frames(animated["double"])
    assert abs(len(double) - len(frames) / 2) <= 1 and len(double) < len(frames)
    assert not list(animated["real_time"].parent.glob(".animation*"))  # no temporary file left


def test_a_frame_shows_the_vehicle_at_its_recorded_position(synthetic_recording: Path,
                                                             animated: dict[str, Path]) -> None:
    """The centre-of-mass marker, found by its colour in the decoded video, is where the recorded position
    (closed form) projects, within 2 px; the marker artist is drawn exactly there."""
    flight = load_flight(synthetic_recording)
    animation = FlightAnimation(build_scene(flight, 10.0, 1.0), AnimationOptions().size)
    _, frames = decoded_frames(animated["real_time"])
    previous = None
    for k in (0, 5, 10, 15, 20):
        t = k / 10
        assert animation.scene.times[k] == pytest.approx(t)
        expected = animation.pixels(view_of(synthetic_position_ned(t)))[0]
        animation.render(k)
        np.testing.assert_allclose(animation.marker_pixel(), expected, atol=1e-6)
        np.testing.assert_allclose(animation.centre_pixel(k), expected, atol=1e-6)
        found = marker_centroid(frames[k], animation, tolerance=40)  # H.264 blurs the colours a little
        np.testing.assert_allclose(found, expected, atol=2.0)
        if previous is not None:
            assert np.linalg.norm(found - previous) > 3  # the vehicle moves between these frames
        previous = found


def test_the_view_is_east_north_up_and_the_rotors_are_the_plants(tmp_path: Path) -> None:
    """A 1 s in-process flight of the tilting quadrotor: rotor centres ``N (p + R p_i)`` and thrust arrows along
    ``N R z_i(alpha_i)`` (fsr_sim's one-sample rotor_axes) in every frame; hovering thrust points up."""
    from fsr_bringup.runner.in_process_flight import fly_in_process
    from fsr_sim.config.scenario import load_scenario

    fly_in_process(load_scenario("ex5_voliro"), recording=tmp_path / "ex5.mcap", max_steps=1000)
    flight = load_flight(open_recording(tmp_path / "ex5.mcap"))
    scene = build_scene(flight, 20.0, 1.0)
    assert scene.frame_count == 21 and np.linalg.det(NED_TO_VIEW) == pytest.approx(1.0)
    np.testing.assert_allclose(view_of([1.0, 2.0, 3.0]), [2.0, 1.0, -3.0])  # (north, east, down) -> (east, north, up)
    vehicle = flight.config.plant_vehicle
    odom, command = flight.odom, flight.rotor_cmd
    for k, t in enumerate(scene.times):
        i = np.searchsorted(odom.t, t + 1e-12) - 1
        j = np.searchsorted(command.t, t + 1e-12) - 1
        p, rotation = odom.position[i], odom.rotation[i]
        np.testing.assert_allclose(scene.centre[k], NED_TO_VIEW @ p, atol=1e-12)
        np.testing.assert_allclose(scene.rotors[k], (p + vehicle.positions @ rotation.T) @ NED_TO_VIEW.T, atol=1e-12)
        if j < 0:
            assert np.all(np.isnan(scene.thrust.vectors[k]))  # no command yet: nothing drawn
            continue
        speed = command.speeds[j]
        thrust = vehicle.c_f * np.abs(speed) * speed
        expected = thrust[:, None] * rotor_axes(vehicle, command.tilts[j]) @ rotation.T @ NED_TO_VIEW.T
        np.testing.assert_allclose(scene.thrust.vectors[k], scene.thrust.metres_per_newton * expected, atol=1e-9)
        np.testing.assert_allclose(scene.thrust.tails[k], scene.rotors[k])
        assert np.all(scene.thrust.vectors[k][:, 2] > 0)  # upright: the rotors push up


def test_animate_gif_writes_a_gif_at_the_asked_pace(synthetic_recording: Path, tmp_path: Path) -> None:
    assert run_cli([str(synthetic_recording), "--out", str(tmp_path), "--no-figures", "--animate", "gif",
                    "--fps", "15"]) == 0
    with Image.open(tmp_path / "animation.gif") as gif:
        assert gif.format == "GIF" and gif.size == AnimationOptions().size
        durations = []
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.append(gif.info["duration"])
        gif.seek(15)  # t = 1 s: the vehicle where the recording has it, in the palette's exact colour
        animation = FlightAnimation(build_scene(load_flight(synthetic_recording), 15.0, 1.0), gif.size)
        expected = animation.pixels(view_of(synthetic_position_ned(1.0)))[0]
        np.testing.assert_allclose(marker_centroid(np.asarray(gif.convert("RGB")), animation, 0), expected, atol=2.0)
    assert len(durations) == 31 and sum(durations) == pytest.approx(31 / 15 * 1000, abs=10)
    assert gif_durations_ms(3, 30.0) == [30, 40, 30]  # 1/30 s is no whole 1/100 s: the sums keep the pace
    assert not (tmp_path / "animation.mp4").exists()


@pytest.mark.parametrize(("extra", "named"), [
    (["--animate", "--speed", "0"], "argument --speed: expected a number > 0; got '0'"),
    (["--animate", "avi"], "argument --animate: invalid choice: 'avi'"),
    (["--animate", "--fps", "-5"], "argument --fps: expected a number > 0; got '-5'"),
    (["--animate", "--speed", "nan"], "argument --speed: expected a number > 0; got 'nan'"),
    (["--speed", "2"], "--speed: only with --animate"),
    (["--animate", "gif", "--fps", "60"], "--fps: a GIF plays at most 50 frames per second; got 60"),
])
def test_bad_animation_options_exit_2_with_one_line(synthetic_recording: Path, tmp_path: Path, capsys,
                                                    extra: list[str], named: str) -> None:
    assert run_cli([str(synthetic_recording), "--out", str(tmp_path / "out"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fsr-analyze: error: ") and named in err[0], err
    assert not (tmp_path / "out").exists()  # refused before anything was written


@pytest.mark.parametrize(("argv", "recordings", "animate"), [
    (["--animate", "run.mcap"], ["run.mcap"], "mp4"),
    (["--animate", "gif", "run.mcap"], ["run.mcap"], "gif"),
    (["--animate", "run.mcap", "--fps", "5"], ["run.mcap"], "mp4"),
    (["run.mcap", "--animate"], ["run.mcap"], "mp4"),
])
def test_animate_may_come_before_the_recording(argv: list[str], recordings: list[str], animate: str) -> None:
    from fsr_bringup.cli.analyze_cli import parse_args

    args = parse_args(argv)
    assert [str(path) for path in args.recordings] == recordings and args.animate == animate


def test_animate_draws_one_recording(synthetic_recording: Path, tmp_path: Path, capsys) -> None:
    assert run_cli([str(synthetic_recording), str(synthetic_recording), "--labels", "a,b", "--out",
                    str(tmp_path / "out"), "--animate"]) == 2
    assert "--animate: draws one recording; got 2" in capsys.readouterr().err


@pytest.mark.parametrize("kind", ["mp4", "gif"])
def test_an_interrupted_animation_leaves_no_file(synthetic_recording: Path, tmp_path: Path, kind: str) -> None:
    """Ctrl-C (KeyboardInterrupt) in the middle of the frames: neither the animation nor its temporary file."""
    def interrupt_at_third(done: int, total: int) -> None:
        if done == 3:
            raise KeyboardInterrupt

    flight = load_flight(synthetic_recording)
    with pytest.raises(KeyboardInterrupt):
        write_animation(flight, tmp_path, AnimationOptions(format=kind, fps=10.0, size=(320, 240)),
                        interrupt_at_third)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("bounds", [[[-5, 5], [-5, 5], [0, 1]], [[-10, 10], [-1, 1], [0, 2]],
                                    [[-1, 1], [-1, 1], [0, 4]]])
def test_the_axis_labels_are_within_the_frame_whatever_the_box(synthetic_recording: Path, bounds) -> None:
    import dataclasses

    from fsr_bringup.analysis.animation import FlightAnimation

    scene = build_scene(load_flight(synthetic_recording), 10.0, 1.0)
    animation = FlightAnimation(dataclasses.replace(scene, bounds=np.array(bounds, float)))
    renderer, frame = animation.canvas.get_renderer(), animation.figure.bbox
    for axis in (animation.axes.xaxis, animation.axes.yaxis, animation.axes.zaxis):
        extent = axis.label.get_window_extent(renderer)
        assert frame.x0 <= extent.x0 and extent.x1 <= frame.x1 and frame.y0 <= extent.y0 and extent.y1 <= frame.y1, (
            axis.label.get_text(), extent)
