"""ROS 2 bags written by other programs — MCAP by mcap-ros2-support, a rosbag2
SQLite folder by rosbags — read through channel maps give the estimate of the
recording's CSV (issue 62). Poses and wrenches come at different rates with
header stamps on a wall clock and log times later by a random latency; trials
are marked by std_msgs/String messages; a JointState topic lists the joints in
another order than the recording, is shared with a gripper's publisher, and
stamps on a simulated clock."""

import json

import numpy as np
import pytest

import limpid
from conftest import examples

mcap_ros2_writer = pytest.importorskip("mcap_ros2.writer")
rosbag2 = pytest.importorskip("rosbags.rosbag2")
typesys = pytest.importorskip("rosbags.typesys")

TYPES = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
WALL = 1_700_000_000_123_456_789  # ns: stamps near 1.7e9 s
AXES = ["x", "y", "z"]


def _load(family, name):
    path = examples(family) / name
    rec = limpid.read_recording(path)
    dt = np.diff(rec["t"])
    assert np.allclose(dt, dt[0], rtol=1e-6), "a uniformly sampled example"
    return path, rec


@pytest.fixture(scope="module")
def cartesian():
    return _load("cartesian_slow", "ex_cubic.csv")


def _stamp(ns):
    return {"sec": int(ns // 1_000_000_000), "nanosec": int(ns % 1_000_000_000)}


def _messages(rec, rng):
    """(log ns, topic, type, message dict) of the 3-D recording: poses at the
    recording's rate, wrenches at twice it (the force interpolated between
    samples, as a faster sensor would see it), a String at each trial start."""
    t = rec["t"]
    out = []
    for i in range(len(t)):
        stamp = WALL + round(t[i] * 1e9)
        pose = {"header": {"stamp": _stamp(stamp), "frame_id": "base"},
                "pose": {"position": {a: float(rec[a][i]) for a in AXES},
                         "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}
        out.append((stamp + int(rng.integers(200_000, 2_000_000)), "/hand_pose",
                    "geometry_msgs/msg/PoseStamped", pose))
    fine = np.arange(2 * len(t) - 1) * (t[1] - t[0]) / 2
    force = {a: np.interp(fine, t, rec["f" + a]) for a in AXES}
    for k, tk in enumerate(fine):
        stamp = WALL + round(tk * 1e9)
        # the sensor reads the force on itself: the hand's force negated
        wrench = {"header": {"stamp": _stamp(stamp), "frame_id": "ft"},
                  "wrench": {"force": {a: -float(force[a][k]) for a in AXES},
                             "torque": {a: 0.0 for a in AXES}}}
        out.append((stamp + int(rng.integers(100_000, 900_000)), "/ft_sensor",
                    "geometry_msgs/msg/WrenchStamped", wrench))
    starts = np.flatnonzero(np.diff(rec["trial"], prepend=rec["trial"][0] - 1) != 0)
    for i in starts:
        out.append((WALL + round(t[i] * 1e9), "/events", "std_msgs/msg/String", {"data": "trial_start"}))
    out.sort(key=lambda m: m[0])
    return out


def _cartesian_map():
    columns = {a: f"/hand_pose.pose.position.{a}" for a in AXES}
    columns.update({"f" + a: {"channel": f"/ft_sensor.wrench.force.{a}", "scale": -1.0} for a in AXES})
    columns["trial"] = {"marker": "trial_start"}
    return {"time": {"stream": "/hand_pose"}, "columns": columns}


def _same_estimate(csv_path, converted, rtol):
    expected = np.asarray(limpid.estimate_linear(csv_path).to_dict()["stiffness"])
    got = np.asarray(limpid.estimate_linear(converted).to_dict()["stiffness"])
    np.testing.assert_allclose(got, expected, rtol=rtol, atol=rtol * np.abs(expected).max())


def _same_samples(converted, rec):
    np.testing.assert_allclose(converted["t"], rec["t"], rtol=0, atol=1e-9)
    for name in AXES + ["fx", "fy", "fz", "trial"]:
        np.testing.assert_allclose(converted[name], rec[name], rtol=1e-12, atol=1e-12)


def test_an_mcap_bag_gives_the_csv_estimate(cartesian, tmp_path):
    path, rec = cartesian
    bag = tmp_path / "session.mcap"
    schemas = {}
    with open(bag, "wb") as f:
        w = mcap_ros2_writer.Writer(f)
        for log, topic, msgtype, msg in _messages(rec, np.random.default_rng(1)):
            if msgtype not in schemas:
                schemas[msgtype] = w.register_msgdef(msgtype, TYPES.generate_msgdef(msgtype, ros_version=2)[0])
            w.write_message(topic, schemas[msgtype], msg, log_time=log, publish_time=log)
        w.finish()
    converted = limpid.read_recording(bag, map=_cartesian_map())
    _same_samples(converted, rec)
    _same_estimate(path, converted, 0.01)


def test_a_rosbag2_sqlite_folder_gives_the_csv_estimate(cartesian, tmp_path):
    path, rec = cartesian
    folder = tmp_path / "session"
    connections = {}
    with rosbag2.Writer(folder, version=8) as w:
        for log, topic, msgtype, msg in _messages(rec, np.random.default_rng(2)):
            if topic not in connections:
                connections[topic] = w.add_connection(topic, msgtype, typestore=TYPES)
            w.write(connections[topic], log, TYPES.serialize_cdr(_typed(msgtype, msg), msgtype))
    assert list(folder.glob("*.db3")), "rosbags wrote a SQLite bag"
    converted = limpid.read_recording(folder, map=_cartesian_map())
    _same_samples(converted, rec)
    _same_estimate(path, converted, 0.01)


def _typed(msgtype, value):
    """A rosbags message object from the dict form mcap-ros2 takes."""
    fields = TYPES.get_msgdef(msgtype).fields
    cls = TYPES.types[msgtype]
    args = {}
    for name, (kind, sub) in fields:
        v = value[name]
        if kind == 2:  # a nested message
            args[name] = _typed(sub, v)
        elif kind == 4 and sub[0][0] == 1 and sub[0][1][0] == "float64":  # a sequence of float64
            args[name] = np.asarray(v, dtype=np.float64)
        else:
            args[name] = v
    return cls(**args)


def test_joint_states_by_name_on_a_simulated_clock(tmp_path):
    """The planar joint example as JointState: names [elbow, shoulder] (q1 the
    second), a gripper's JointState interleaved on the same topic, header
    stamps counted from 0 (simulated time) and log times on the wall clock
    with jitter: the map takes the log times, dejittered."""
    path, rec = _load("planar", "ex_joint_180.csv")
    rng = np.random.default_rng(3)
    bag = tmp_path / "arm.mcap"
    msgtype = "sensor_msgs/msg/JointState"
    with open(bag, "wb") as f:
        w = mcap_ros2_writer.Writer(f)
        schema = w.register_msgdef(msgtype, TYPES.generate_msgdef(msgtype, ros_version=2)[0])
        text = w.register_msgdef("std_msgs/msg/String", "string data")
        starts = set(np.flatnonzero(np.diff(rec["trial"], prepend=rec["trial"][0] - 1) != 0))
        for i, t in enumerate(rec["t"]):
            if i in starts:
                ns = WALL + round(t * 1e9)
                w.write_message("/events", text, {"data": "trial"}, log_time=ns, publish_time=ns)
            log = WALL + round(t * 1e9) + int(rng.integers(0, 400_000))
            arm = {"header": {"stamp": _stamp(round(t * 1e9)), "frame_id": ""},
                   "name": ["elbow", "shoulder"],
                   "position": [float(rec["q2"][i]), float(rec["q1"][i])],
                   "velocity": [],
                   "effort": [float(rec["tau2"][i]), float(rec["tau1"][i])]}
            w.write_message("/joint_states", schema, arm, log_time=log, publish_time=log)
            if i % 10 == 0:
                gripper = {"header": {"stamp": _stamp(round(t * 1e9)), "frame_id": ""},
                           "name": ["gripper"], "position": [0.01], "velocity": [0.0], "effort": [0.0]}
                w.write_message("/joint_states", schema, gripper, log_time=log + 1, publish_time=log + 1)
        w.finish()
    columns = {"q1": "/joint_states.position[shoulder]", # the index form is in both shapes' streams: the map names the arm's
               "q2": {"channel": "/joint_states.position[0]", "stream": "/joint_states"},
               "tau1": "/joint_states.effort[shoulder]", "tau2": "/joint_states.effort[elbow]",
               "trial": {"marker": "trial"}}
    lab_map = {"time": {"stream": "/joint_states"}, "columns": columns,
               "streams": {"/joint_states": {"clock": "log", "dejitter": True}}}
    converted = limpid.read_recording(bag, map=lab_map)
    for name in ["q1", "q2", "tau1", "tau2"]:
        np.testing.assert_allclose(converted[name], rec[name], rtol=1e-12, atol=1e-12)
    # the dejittered log times: the recording's grid within the jitter's mean
    np.testing.assert_allclose(converted["t"], rec["t"], rtol=0, atol=2e-5)
    truth_links = json.loads(path.with_suffix(".truth.json").read_text())["link_lengths"]
    expected = limpid.estimate_planar(path, truth_links).to_dict()
    got = limpid.estimate_planar(converted, truth_links).to_dict()
    k_expected, k_got = np.asarray(expected["stiffness"]), np.asarray(got["stiffness"])
    np.testing.assert_allclose(k_got, k_expected, rtol=0.01, atol=0.01 * np.abs(k_expected).max())


def test_a_custom_message_type_is_read_from_its_stored_definition(tmp_path):
    bag = tmp_path / "custom.mcap"
    definition = ("std_msgs/Header header\nfloat64[3] position\nfloat32 grip  # N\n"
                  "uint8 MODE_FREE=0\nstring note\n"
                  "================================================================================\n"
                  "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
                  "================================================================================\n"
                  "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
    with open(bag, "wb") as f:
        w = mcap_ros2_writer.Writer(f)
        schema = w.register_msgdef("lab_msgs/msg/Handle", definition)
        for k in range(200):
            ns = WALL + k * 2_000_000
            msg = {"header": {"stamp": _stamp(ns), "frame_id": "h"},
                   "position": [0.1 * k, -0.2 * k, 0.5], "grip": float(k), "note": "ok"}
            w.write_message("/handle", schema, msg, log_time=ns + 500_000, publish_time=ns)
        w.finish()
    got = limpid.read_recording(bag, map={"columns": {"x": "/handle.position[0]", "y": "/handle.position[1]",
                                                      "z": "/handle.position[2]"}})
    np.testing.assert_allclose(got["t"], np.arange(200) * 0.002, atol=1e-12)
    np.testing.assert_allclose(got["x"], 0.1 * np.arange(200), atol=1e-12)
    np.testing.assert_allclose(got["y"], -0.2 * np.arange(200), atol=1e-12)
