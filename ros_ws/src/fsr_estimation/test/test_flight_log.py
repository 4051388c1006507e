import numpy as np
import pytest
import scipy.io

from fsr_estimation.io.flight_log import (
    FlightLog,
    FlightLogError,
    _topic_arrays,
    load_csv,
    load_flight_log,
    load_mat,
    load_mcap,
    write_mcap,
)


def small_log(n=50, synthetic=None):
    rng = np.random.default_rng(1)
    return FlightLog(time=np.arange(n) * 0.001, eta=rng.uniform(-0.4, 0.4, (n, 3)), eta_dot=rng.normal(size=(n, 3)),
                     velocity_world=rng.normal(size=(n, 3)), force_body=rng.normal(size=(n, 3)),
                     torque_body=rng.normal(size=(n, 3)), source="small")


def fields(log):
    return {name: getattr(log, name) for name in ("time", "eta", "eta_dot", "velocity_world", "force_body",
                                                  "torque_body")}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda f: f.update(eta=f["eta"][:, :2]), r"eta: expected shape \(N, 3\)"),
        (lambda f: f.update(torque_body=f["torque_body"][:-1]), "torque_body: has 49 samples, time has 50"),
        (lambda f: f["velocity_world"].__setitem__((7, 1), np.nan), "velocity_world: NaN or inf at sample 7"),
        (lambda f: f["force_body"].__setitem__((3, 0), np.inf), "force_body: NaN or inf at sample 3"),
        (lambda f: f["time"].__setitem__(10, f["time"][9]), "time: not increasing at sample 10"),
        (lambda f: f["time"].__setitem__(slice(20, None), f["time"][20:] + 0.0005), "non-uniform time base"),
        (lambda f: [f.update({k: v[:5]}) for k, v in list(f.items())], "too few samples"),
    ],
)
def test_bad_logs_are_refused_with_the_reason(change, message):
    f = {k: v.copy() for k, v in fields(small_log()).items()}
    change(f)
    with pytest.raises(FlightLogError, match=message) as error:
        FlightLog(**f, source="bad.csv")
    assert str(error.value).startswith("bad.csv: ")


def test_mat_layout_and_its_refusals(tmp_path, report_mat):
    report_log = load_mat(report_mat)
    assert len(report_log) == 30001 and report_log.sample_time == pytest.approx(0.001, rel=1e-12)
    np.testing.assert_array_equal(report_log.force_body[:, :2], 0.0)
    assert np.all(report_log.force_body[:, 2] < 0.0)  # thrust along -z_b
    n = 20
    struct = {"time": np.arange(n)[:, None] * 0.001, "signals": {"values": np.zeros((n, 3)), "dimensions": 3}}
    data = {name: struct for name in ("attitude", "attitude_vel", "linear_vel", "tau")}
    scipy.io.savemat(tmp_path / "partial.mat", data)
    with pytest.raises(FlightLogError, match="missing field.*thrust"):
        load_mat(tmp_path / "partial.mat")
    data["thrust"] = {"time": struct["time"], "signals": {"values": np.full((n, 2), 9.81)}}
    scipy.io.savemat(tmp_path / "wide.mat", data)
    with pytest.raises(FlightLogError, match="thrust.signals.values: expected shape"):
        load_mat(tmp_path / "wide.mat")
    (tmp_path / "junk.mat").write_bytes(b"not a mat file at all" * 10)
    with pytest.raises(FlightLogError, match="junk.mat"):
        load_mat(tmp_path / "junk.mat")


def test_csv_with_thrust_or_body_force(tmp_path):
    log = small_log()
    header = "time,roll,pitch,yaw,roll_rate,pitch_rate,yaw_rate,vx,vy,vz,fx,fy,fz,tx,ty,tz"
    table = np.column_stack((log.time, log.eta, log.eta_dot, log.velocity_world, log.force_body, log.torque_body))
    np.savetxt(tmp_path / "force.csv", table, delimiter=",", header=header, comments="", fmt="%.17g")
    loaded = load_flight_log(tmp_path / "force.csv")
    for name, value in fields(log).items():
        np.testing.assert_array_equal(getattr(loaded, name), value)
    thrust_header = header.replace("fx,fy,fz", "thrust")
    table = np.column_stack((log.time, log.eta, log.eta_dot, log.velocity_world, np.full(50, 12.0), log.torque_body))
    np.savetxt(tmp_path / "thrust.csv", table, delimiter=",", header=thrust_header, comments="", fmt="%.17g")
    np.testing.assert_array_equal(load_csv(tmp_path / "thrust.csv").force_body, [[0.0, 0.0, -12.0]] * 50)
    (tmp_path / "short.csv").write_text("time,roll\n0,0\n")
    with pytest.raises(FlightLogError, match="missing column.*pitch.*CSV columns"):
        load_csv(tmp_path / "short.csv")


def test_unknown_extension_and_missing_file_are_refused(tmp_path):
    with pytest.raises(FlightLogError, match="unknown log format '.bag'"):
        load_flight_log(tmp_path / "x.bag")
    with pytest.raises(FlightLogError, match="no such file"):
        load_flight_log(tmp_path / "x.mcap")


def test_mcap_round_trip_is_lossless_to_rounding(tmp_path):
    log = small_log(200)
    path = write_mcap(log, tmp_path / "log.mcap")
    loaded = load_mcap(path)
    for name, value in fields(log).items():
        np.testing.assert_allclose(getattr(loaded, name), value, rtol=0.0, atol=1e-12, err_msg=name)


def test_vectorised_cdr_path_equals_the_generic_decoder(tmp_path):
    from fsr_sim.recording.reader import open_recording

    log = small_log(30)
    recording = open_recording(write_mcap(log, tmp_path / "log.mcap"))
    for topic in ("odom", "wrench_cmd"):
        stamps, values = _topic_arrays(recording, topic)
        decoded = recording.messages(topic)
        assert stamps.tolist() == [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in decoded]
        if topic == "wrench_cmd":
            np.testing.assert_array_equal(values, [[m.wrench.force.x, m.wrench.force.y, m.wrench.force.z,
                                                    m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z]
                                                   for _, m in decoded])
        else:
            np.testing.assert_array_equal(values[:, 3:7], [[m.pose.pose.orientation.x, m.pose.pose.orientation.y,
                                                            m.pose.pose.orientation.z, m.pose.pose.orientation.w]
                                                           for _, m in decoded])
            np.testing.assert_array_equal(values[:, 10:13], [[m.twist.twist.angular.x, m.twist.twist.angular.y,
                                                              m.twist.twist.angular.z] for _, m in decoded])


def test_topic_with_two_frame_ids_is_decoded_per_layout(tmp_path):
    from fsr_sim.recording.writer import RecordingWriter
    from fsr_sim.ros.conversions import wrench_stamped

    messages = [wrench_stamped(k * 10**6, np.array([k, 2.0 * k, 3.0]), np.array([0.5, -k, 0.0])) for k in range(12)]
    messages[4].header.frame_id = "another_frame"  # another string length: a second byte layout
    with RecordingWriter(tmp_path / "mixed.mcap") as writer:
        for k, msg in enumerate(messages):
            writer.write_message("/wrench_cmd", msg, k * 10**6)
    from fsr_sim.recording.reader import open_recording

    stamps, values = _topic_arrays(open_recording(tmp_path / "mixed.mcap"), "wrench_cmd")
    assert stamps.tolist() == [k * 10**6 for k in range(12)]
    np.testing.assert_array_equal(values, [[k, 2.0 * k, 3.0, 0.5, -k, 0.0] for k in range(12)])


def test_mcap_without_the_wrench_topic_is_refused(tmp_path):
    from fsr_sim.recording.writer import RecordingWriter
    from fsr_sim.ros.conversions import odometry_from_state

    with RecordingWriter(tmp_path / "odom_only.mcap") as writer:
        for k in range(20):
            writer.write_message("/odom", odometry_from_state(k * 10**6, np.zeros(3), np.eye(3), np.zeros(3),
                                                              np.zeros(3)), k * 10**6)
    with pytest.raises(FlightLogError, match="no topic 'wrench_cmd'"):
        load_mcap(tmp_path / "odom_only.mcap")
