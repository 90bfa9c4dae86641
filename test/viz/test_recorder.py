"""TelemetryRecorder into .rrd files, read back with rerun's chunk API (no DDS, no viewer)."""

from __future__ import annotations

import math
from collections import defaultdict
from datetime import timedelta

import numpy as np
import pinocchio as pin
import pytest
from rerun.chunk import RrdReader
from rns_testing import SATELLITE_OBSERVATION_DEG, run_with_file_size_limit

from rns_ros.core import ConfigError, FreeFloatingState, InputError, load_model_config
from rns_ros.resources import default_model_config
from rns_ros.viz import RecorderSettings, SinkSettings, TelemetryRecorder, paths
from rns_ros.viz.readback import (
    read_components,
    read_scalars,
    recording_ids,
    recording_summary,
)
from rns_ros.viz.recorder import FRUSTUM_DEPTH

PERIOD_NS = 10_000_000  # 100 Hz
STATUS = {
    "state": "OK",
    "method": "dls",
    "frame": "world",
    "sigma_min": "0.3",
    "det_kinematic": "11",
    "det_coupling": "1.3e+13",
    "det_algorithmic": "0.2",
    "damping": "0",
    "speed_scale": "1",
    "unachieved_angular": "0 0 0",
    "unachieved_linear": "0 0 0",
    "coupling_momentum": "3e-16 -1e-16 2e-16",
}


@pytest.fixture
def open_recorder(robot, tmp_path):
    """Factory: a recorder saving to tmp_path/<name>.rrd; all are closed at teardown."""
    urdf, _ = load_model_config(default_model_config())
    recorders = []

    def factory(name="run", clock=None, **settings):
        sink = SinkSettings(kind="save", rrd_path=tmp_path / f"{name}.rrd")
        recorder = TelemetryRecorder(robot, urdf, sink, RecorderSettings(**settings), clock=clock)
        recorders.append(recorder)
        return recorder

    yield factory
    for recorder in recorders:
        recorder.close()


#: One sample of rns_simulator's energy topic (its labels) [J, J s].
ENERGY = {
    "base": 0.1,
    "arm": 2.0,
    "coupling": -0.05,
    "wheels": 0.0,
    "total": 2.05,
    "lambda_arm": 1.9,
    "lambda_wheels": 40.0,
    "c_max": 41.9,
    "c_sum": 12.0,
}


def _theta(k: int) -> np.ndarray:
    return np.radians(SATELLITE_OBSERVATION_DEG) + 0.002 * k


def _base_quaternion(k: int) -> np.ndarray:
    """Base yawing 0.01 deg per sample (x y z w)."""
    half = math.radians(0.01 * k) / 2
    return np.array([0.0, 0.0, math.sin(half), math.cos(half)])


class _Clock:
    """The recorder's wall clock, set by the test [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _feed(recorder, samples: int, start_ns: int = 0, clock: _Clock | None = None) -> None:
    """What the simulator + controller + operator publish at 100 Hz, for ``samples`` periods;
    with ``clock``, the recorder's wall clock follows the stamps (a run as it happens)."""
    for k in range(samples):
        stamp = start_ns + k * PERIOD_NS
        if clock is not None:
            clock.now = k * PERIOD_NS * 1e-9
        recorder.base_odom(stamp, [0.1, 0.0, 0.0], _base_quaternion(k), [0.0, 0.0, 0.001])
        recorder.joint_state(stamp, _theta(k), np.full(7, 0.2))
        recorder.momentum(stamp, [0.0, 0.0, 0.0], [1e-12, 0.0, 0.0])
        recorder.controller_status(stamp, STATUS, 0, "")
        recorder.commanded_twist(stamp, [0.0, 0.0, 0.1], "world")
        recorder.energy(stamp, ENERGY | {"time": k * 0.01})
        recorder.wheel_state(stamp, [1.0, 2.0, 3.0], [0.01, 0.0, -0.1])


def _series_paths(robot) -> list[str]:
    """Every series the teleoperation stack feeds (rns_ptp's are tested on their own)."""
    return [p for p in paths.series_table(robot.joint_names) if not p.startswith(paths.PTP)]


def test_every_documented_series_has_one_sample_per_message(open_recorder, robot):
    recorder = open_recorder(recording_name="dls")
    _feed(recorder, 50)
    recorder.close()
    summary = recording_summary(recorder.sink.rrd_path)
    for path in _series_paths(robot):
        assert summary.get(path) == 50, path
    for joint in robot.joint_names:
        assert summary[paths.joint_transform(joint)] == 50
    assert summary[paths.BASE_POSE] == 50
    assert summary[paths.CAMERA_POINTING] == 50
    assert summary[paths.CAMERA_TRAIL] == 5  # one point per 0.1 s of stamps
    assert summary[paths.CONTROLLER_LOG] == 1  # the state never changed
    # the URDF model: every link's visual geometry, static, plus the fixed joint origins
    visuals = recorder.view.visual_paths()
    assert set(visuals) == {"base_link", *(f"link_{i}" for i in range(1, 8)), "camera", "wrist"}
    for link_paths in visuals.values():
        for path in link_paths:
            assert summary[path] == 0  # present, static only
    assert summary["tf_static"] == 0
    assert recording_summary(recorder.sink.rrd_path, include_static=True)["tf_static"] == 9


def test_saved_file_is_complete_after_close(open_recorder):
    recorder = open_recorder()
    _feed(recorder, 5)
    assert not recorder.closed
    recorder.close()
    recorder.close()  # idempotent
    recorder.joint_state(10**9, _theta(0), np.zeros(7))  # ignored after close
    reader = RrdReader(recorder.sink.rrd_path)
    # store() needs the footer (manifest) that only a finalized file has
    store = reader.store()
    assert len(store) > 0
    assert len(reader.blueprints()) == 1  # the default layout travels with the file


def test_plotted_values_and_sim_time_come_back(open_recorder):
    recorder = open_recorder()
    _feed(recorder, 30)
    recorder.close()
    rrd = recorder.sink.rrd_path
    times, yaw = read_scalars(rrd, paths.BASE_ATTITUDE_YAW)
    assert times == pytest.approx(np.arange(30) * 0.01)  # stamps from 0: a duration timeline
    assert yaw == pytest.approx(0.01 * np.arange(30), abs=1e-9)  # relative to the first odom
    _, total = read_scalars(rrd, paths.BASE_ATTITUDE_TOTAL)
    assert total == pytest.approx(yaw, abs=1e-9)
    _, coupling_x = read_scalars(rrd, paths.COUPLING_MOMENTUM_AXES[0])
    assert coupling_x == pytest.approx(np.full(30, 3e-16))
    _, sigma = read_scalars(rrd, paths.SIGMA_MIN)
    assert np.all(sigma == 0.3)
    _, state = read_scalars(rrd, paths.CONTROLLER_STATE)
    assert np.all(state == paths.CONTROLLER_STATE_CODES["OK"])
    _, commanded_z = read_scalars(rrd, paths.COMMANDED_ANGULAR_VELOCITY_AXES[2])
    assert np.all(commanded_z == 0.1)
    _, joint_velocity = read_scalars(rrd, paths.joint_velocity("joint_3"))
    assert np.all(joint_velocity == 0.2)
    _, angular = read_scalars(rrd, paths.MOMENTUM_ANGULAR)
    assert angular == pytest.approx(np.full(30, 1e-12))


def test_wall_clock_stamps_make_a_timestamp_timeline(open_recorder):
    recorder = open_recorder()
    start = 1_700_000_000 * 10**9 + 123  # nanoseconds since the epoch, kept exactly
    _feed(recorder, 3, start_ns=start)
    recorder.close()
    times, _ = read_scalars(recorder.sink.rrd_path, paths.BASE_ATTITUDE_ROLL)
    assert times == pytest.approx(1.7e9 + np.arange(3) * 0.01, abs=1e-6)


def test_logged_frame_tree_places_the_camera_where_pinocchio_does(open_recorder, robot):
    """Compose what the viewer composes: world -> base (base_pose), then the joint transforms
    from the URDF's parent to child links, then the fixed camera joint from /tf_static."""
    recorder = open_recorder()
    theta = _theta(7)
    quaternion = pin.Quaternion(pin.rpy.rpyToMatrix(0.2, -0.1, 0.7)).coeffs()
    position = [0.3, -0.2, 1.5]
    recorder.base_odom(0, position, quaternion)
    recorder.joint_state(0, theta)
    recorder.close()
    rrd = recorder.sink.rrd_path

    def transform(row) -> pin.SE3:
        x, y, z, w = row["Transform3D:quaternion"][0]
        rotation = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
        return pin.SE3(rotation, np.array(row["Transform3D:translation"][0]))

    edges = {}  # child frame -> (parent frame, transform)
    for row in read_components(rrd, "tf_static"):
        edges[row["Transform3D:child_frame"][0]] = (row["Transform3D:parent_frame"][0], row)
    for path in [paths.BASE_POSE, *(paths.joint_transform(j) for j in robot.joint_names)]:
        (row,) = read_components(rrd, path)
        edges[row["Transform3D:child_frame"][0]] = (row["Transform3D:parent_frame"][0], row)
    pose, frame = pin.SE3.Identity(), "camera"
    while frame != paths.WORLD_FRAME_ID:
        parent, row = edges[frame]
        pose = transform(row) * pose
        frame = parent

    state = FreeFloatingState.compute(robot, robot.configuration(theta, position, quaternion))
    assert pose.translation == pytest.approx(state.camera.position, abs=2e-6)  # float32 rows
    assert pose.rotation == pytest.approx(state.camera.rotation, abs=2e-6)
    (arrow,) = [r for r in read_components(rrd, paths.CAMERA_POINTING) if "Arrows3D:vectors" in r]
    assert arrow["Arrows3D:origins"][0] == pytest.approx(state.camera.position, abs=1e-6)
    direction = np.array(arrow["Arrows3D:vectors"][0])
    assert direction / np.linalg.norm(direction) == pytest.approx(
        state.camera.rotation[:, 2], abs=1e-6
    )


def test_three_recordings_in_one_process_make_three_complete_files(open_recorder):
    recorders = [open_recorder(name, recording_name=name) for name in ("dls", "sc", "conv")]
    for count, recorder in enumerate(recorders, start=1):
        _feed(recorder, 10 * count)
    for recorder in recorders:
        recorder.close()
    ids = set()
    for count, recorder in enumerate(recorders, start=1):
        ((application, recording),) = recording_ids(recorder.sink.rrd_path)
        assert application == "rns_ros"
        ids.add(recording)
        summary = recording_summary(recorder.sink.rrd_path)
        assert summary[paths.BASE_ATTITUDE_TOTAL] == 10 * count
        names = [
            row.get("RecordingInfo:name")
            for row in read_components(recorder.sink.rrd_path, "__properties")
        ]
        assert [recorder.settings.recording_name] in names
    assert len(ids) == 3


def test_max_rate_thins_a_fast_stream(open_recorder):
    recorder = open_recorder(max_rate=200.0)
    for k in range(100):  # 1 kHz for 0.1 s
        recorder.joint_state(k * 1_000_000, _theta(k), np.zeros(7))
    recorder.close()
    assert recorder.counts["joints"] == 20
    assert recording_summary(recorder.sink.rrd_path)[paths.joint_transform("joint_1")] == 20


def test_commanded_twist_is_turned_into_world_axes(open_recorder, robot):
    recorder = open_recorder(max_rate=0.0)
    # camera axes need the camera: nothing before the first joint state
    assert not recorder.commanded_twist(0, [0.1, 0.0, 0.0], "camera")
    quaternion = [0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)]  # base yawed 90 deg
    recorder.base_odom(0, [0.0, 0.0, 0.0], quaternion)
    assert recorder.commanded_twist(1, [0.1, 0.0, 0.0], "base")  # base x = world y
    recorder.joint_state(2, _theta(0))
    assert recorder.commanded_twist(3, [0.0, 0.0, 0.1], "camera")  # along the optical axis
    with pytest.raises(ConfigError, match="twist frame"):
        recorder.commanded_twist(4, [0.0, 0.0, 0.1], "map")
    with pytest.raises(InputError, match="finite"):
        recorder.commanded_twist(4, [math.nan, 0.0, 0.0], "world")
    recorder.close()
    omega = np.array(
        [read_scalars(recorder.sink.rrd_path, p)[1] for p in paths.COMMANDED_ANGULAR_VELOCITY_AXES]
    ).T
    assert omega.shape == (2, 3)
    assert omega[0] == pytest.approx([0.0, 0.1, 0.0], abs=1e-12)
    assert omega[1] == pytest.approx(0.1 * recorder.state.camera.rotation[:, 2], abs=1e-12)


def test_controller_log_records_state_changes_only(open_recorder):
    recorder = open_recorder()
    states = ["OK", "OK", "SINGULAR_REGION", "SINGULAR_REGION", "INVALID_COMMAND", "OK"]
    for k, state in enumerate(states):
        level = 2 if state == "INVALID_COMMAND" else 0
        message = f"{state}: frame 'map' is not one of" if level else ""
        recorder.controller_status(k * PERIOD_NS, {**STATUS, "state": state}, level, message)
    recorder.controller_status(len(states) * PERIOD_NS, {"sigma_min": "0.5"})  # partial status
    recorder.close()
    rrd = recorder.sink.rrd_path
    log = read_components(rrd, paths.CONTROLLER_LOG)
    assert [row["TextLog:text"][0].split(":")[0] for row in log] == [
        "OK",
        "SINGULAR_REGION",
        "INVALID_COMMAND",
        "OK",
    ]
    assert [row["TextLog:level"][0] for row in log] == ["INFO", "INFO", "ERROR", "INFO"]
    _, codes = read_scalars(rrd, paths.CONTROLLER_STATE)
    assert codes.tolist() == [0, 0, 2, 2, 5, 0]
    assert read_scalars(rrd, paths.SIGMA_MIN)[1].tolist() == [0.3] * 6 + [0.5]


def test_bad_inputs_raise_typed_errors_and_leave_the_recording_usable(open_recorder):
    recorder = open_recorder()
    with pytest.raises(InputError, match="shape"):
        recorder.joint_state(0, np.zeros(6))
    with pytest.raises(InputError, match="non-zero"):
        recorder.base_odom(0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0])
    _feed(recorder, 3)
    recorder.close()
    assert recording_summary(recorder.sink.rrd_path)[paths.BASE_ATTITUDE_TOTAL] == 3


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"trail_length": -1}, "trail_length"),
        ({"max_rate": -5.0}, "max_rate"),
        ({"application_id": ""}, "application_id"),
        ({"flush_tick": 0.0}, "flush_tick"),
        ({"flush_tick": 3600.0}, "flush_tick"),
        ({"file_flush_tick": -1.0}, "file_flush_tick"),
        ({"flush_num_rows": 0}, "flush_num_rows"),
        ({"flush_num_bytes": 0}, "flush_num_bytes"),
    ],
)
def test_bad_settings_are_config_errors(settings, message):
    with pytest.raises(ConfigError, match=message):
        RecorderSettings(**settings)


def _rows_per_chunk(path, *, static: bool = False) -> dict[str, list[int]]:
    """{entity path: rows of each of its chunks, in file order} of the file's recording; static
    chunks only with ``static``."""
    rows = defaultdict(list)
    for chunk in RrdReader(path).stream():
        if static or not chunk.is_static:
            rows[chunk.entity_path.lstrip("/") or "/"].append(chunk.num_rows)
    return rows


@pytest.mark.parametrize("tick", ["file_flush_tick", "flush_tick"])
def test_a_run_at_its_own_pace_is_saved_in_chunks_of_many_rows(open_recorder, robot, tick):
    """25 s at 100 Hz with the recorder's clock following the stamps: each 100 Hz entity is
    sent once per tick (a file's, or a live viewer's 1 s: 100 rows a chunk), no sample lost."""
    clock = _Clock()
    recorder = open_recorder(clock=clock, file_flush_tick=getattr(RecorderSettings(), tick))
    _feed(recorder, 2500, clock=clock)
    recorder.close()
    every = _rows_per_chunk(recorder.sink.rrd_path, static=True)
    chunks = [count for counts in every.values() for count in counts]
    assert sum(chunks) / len(chunks) >= 50  # static chunks (URDF, styles) included
    rows = _rows_per_chunk(recorder.sink.rrd_path)
    blocks = math.ceil(25.0 / recorder.flush_tick) + 1
    for path in [*_series_paths(robot), paths.BASE_POSE, paths.CAMERA_POINTING]:
        assert sum(rows[path]) == 2500, path
        assert len(rows[path]) <= blocks, (path, rows[path])
    for joint in robot.joint_names:
        assert sum(rows[paths.joint_transform(joint)]) == 2500
        assert len(rows[paths.joint_transform(joint)]) <= blocks
    # logged one row at a time: batched by rerun into few chunks too
    assert sum(rows[paths.CAMERA_TRAIL]) == 250
    assert len(rows[paths.CAMERA_TRAIL]) < 250
    times, yaw = read_scalars(recorder.sink.rrd_path, paths.BASE_ATTITUDE_YAW)
    assert times == pytest.approx(np.arange(2500) * 0.01)
    assert yaw == pytest.approx(0.01 * np.arange(2500), abs=1e-9)


def test_an_entity_with_flush_num_rows_rows_is_sent_before_the_tick(open_recorder, robot):
    """The clock stands still: blocks go out when they are full (and the rest on close); rows
    logged one at a time obey the same limit in rerun's batcher."""
    recorder = open_recorder(clock=_Clock(), flush_num_rows=20, file_flush_tick=60.0)
    _feed(recorder, 50)
    assert recorder.pending_rows == 10
    recorder.close()
    rows = _rows_per_chunk(recorder.sink.rrd_path)
    for path in [*_series_paths(robot), paths.BASE_POSE, paths.joint_transform("joint_4")]:
        assert rows[path] == [20, 20, 10], path
    assert all(count <= 20 for count in rows[paths.CAMERA_TRAIL])


def test_a_sample_waits_at_most_one_flush_tick(open_recorder):
    """The node's timer calls send_due: samples leave once flush_tick has passed since the last
    block, also when no further message comes."""
    clock = _Clock()
    recorder = open_recorder(clock=clock, file_flush_tick=0.5)
    assert recorder.flush_tick == 0.5
    config = recorder.settings.batcher_config("save")
    assert config.flush_tick == timedelta(seconds=0.5)  # rerun's batcher ticks alike
    assert config.flush_num_rows == recorder.settings.flush_num_rows
    recorder.joint_state(0, _theta(0), np.zeros(7))
    assert recorder.pending_rows == 1
    clock.now = 0.49
    recorder.send_due()
    assert recorder.pending_rows == 1
    clock.now = 0.5
    recorder.send_due()
    assert recorder.pending_rows == 0
    recorder.joint_state(PERIOD_NS, _theta(1), np.zeros(7))  # a new block, a new tick
    clock.now = 0.9
    recorder.send_due()
    assert recorder.pending_rows == 1
    recorder.close()
    assert recording_summary(recorder.sink.rrd_path)[paths.joint_transform("joint_1")] == 2


def test_live_sinks_get_the_short_tick_and_files_the_long_one():
    settings = RecorderSettings()
    for kind in ("spawn", "connect", "serve"):
        assert settings.tick(kind) == settings.flush_tick == 1.0
        assert settings.batcher_config(kind).flush_tick == timedelta(seconds=1.0)
    assert settings.tick("save") == settings.file_flush_tick == 10.0
    assert settings.batcher_config("save").flush_num_bytes == settings.flush_num_bytes


def test_ptp_phase_progress_and_log_follow_the_status(open_recorder):
    recorder = open_recorder()
    steps = [
        ("IDLE", None, None),
        ("PLANNING", None, None),
        ("MOVING", "I", 0.1),
        ("MOVING", "I", 0.2),
        ("MOVING", "II", 0.5),
        ("MOVING", "III", 0.9),
        ("DONE", "done", 1.0),
    ]
    for k, (state, phase, progress) in enumerate(steps):
        values = {"state": state, "coupling_momentum": str(0.01 * k)}
        if phase is not None:
            values |= {"phase": phase, "progress": str(progress)}
        recorder.ptp_status(k * PERIOD_NS, values, 0, state)
    recorder.close()
    rrd = recorder.sink.rrd_path
    assert read_scalars(rrd, paths.PTP_PHASE)[1].tolist() == [1, 1, 2, 3, 0]
    assert read_scalars(rrd, paths.PTP_PROGRESS)[1].tolist() == [0.1, 0.2, 0.5, 0.9, 1.0]
    norm = read_scalars(rrd, paths.COUPLING_MOMENTUM_NORM)[1]
    assert norm == pytest.approx([0.01 * k for k in range(7)])
    log = [row["TextLog:text"][0] for row in read_components(rrd, paths.PTP_LOG)]
    assert log == [
        "IDLE",
        "PLANNING",
        "phase I: MOVING",
        "phase II: MOVING",
        "phase III: MOVING",
        "phase done: DONE",
    ]


def test_the_grounds_arms_are_ghosts_of_their_configurations(open_recorder, robot):
    """The predicted and the telemetry arm: base, joint origins and camera of the configuration
    given, each under its own path, at its own stamp; a bad one is refused by name."""
    recorder = open_recorder()
    theta = np.radians([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
    q = robot.configuration(theta, [0.3, -0.2, 0.1], _base_quaternion(500))
    recorder.ground_arm("predicted", PERIOD_NS, q)
    recorder.ground_arm("telemetry", 2 * PERIOD_NS, robot.configuration(robot.initial_theta))
    with pytest.raises(InputError, match="ground arm must be one of"):
        recorder.ground_arm("future", 3 * PERIOD_NS, q)
    with pytest.raises(InputError, match="predicted arm q"):
        recorder.ground_arm("predicted", 3 * PERIOD_NS, [math.nan] * robot.model.nq)
    recorder.close()
    rrd = recorder.sink.rrd_path
    strips = [r for r in read_components(rrd, paths.PREDICTED_ARM) if "LineStrips3D:strips" in r]
    assert len(strips) == 1
    points = np.array(strips[0]["LineStrips3D:strips"][0])
    camera = FreeFloatingState.compute(robot, q).camera.position
    np.testing.assert_allclose(points[0], [0.3, -0.2, 0.1], atol=1e-6)
    np.testing.assert_allclose(points[-1], camera, atol=1e-6)
    telemetry = read_components(rrd, paths.TELEMETRY_ARM)
    assert sum("LineStrips3D:strips" in r for r in telemetry) == 1


def test_the_predicted_camera_is_a_frustum_at_the_predicted_camera_pose(open_recorder, robot):
    """A pinhole (+z forward) under the camera pose of the predicted configuration: the pose is
    the one FreeFloatingState computes for that configuration."""
    recorder = open_recorder()
    theta = np.radians([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
    q = robot.configuration(theta, [0.3, -0.2, 0.1], _base_quaternion(500))
    recorder.ground_arm("predicted", PERIOD_NS, q)
    recorder.ground_arm("telemetry", 2 * PERIOD_NS, q)  # the telemetry arm has none
    recorder.close()
    rows = read_components(recorder.sink.rrd_path, paths.PREDICTED_CAMERA)
    (pose,) = [r for r in rows if "Transform3D:translation" in r]
    camera = FreeFloatingState.compute(robot, q).camera
    np.testing.assert_allclose(pose["Transform3D:translation"][0], camera.position, atol=1e-6)
    matrix = np.array(pose["Transform3D:mat3x3"][0]).reshape(3, 3).T  # stored column-major
    np.testing.assert_allclose(matrix, camera.rotation, atol=1e-6)
    (pinhole,) = [r for r in rows if "Pinhole:image_from_camera" in r]
    assert pinhole["Pinhole:image_plane_distance"] == [pytest.approx(FRUSTUM_DEPTH)]


def test_the_grounds_status_figures_are_time_series(open_recorder):
    """rns_predictor's prediction error and rns_link's delay, messages in flight and lost per
    direction become scalars; a value that is not a finite number is skipped."""
    recorder = open_recorder()
    predictor = {"prediction_error_camera_deg": "0.0125", "prediction_error_base_deg": "nan"}
    link = {"uplink last delay [s]": "3.0004", "uplink in flight": "151", "downlink lost": "x"}
    assert recorder.ground_status("predictor", PERIOD_NS, predictor) == 1
    assert recorder.ground_status("link", PERIOD_NS, link) == 2  # its own stream: same stamp
    with pytest.raises(InputError, match="ground status source must be"):
        recorder.ground_status("uplink", 2 * PERIOD_NS, link)
    recorder.close()
    rrd = recorder.sink.rrd_path
    _, camera = read_scalars(rrd, paths.PREDICTION_ERROR_CAMERA)
    assert camera.tolist() == [pytest.approx(0.0125)]
    assert read_scalars(rrd, paths.PREDICTION_ERROR_BASE)[1].size == 0
    _, delay = read_scalars(rrd, f"{paths.LINK}/uplink/delay_s")
    assert delay.tolist() == [pytest.approx(3.0004)]
    _, in_flight = read_scalars(rrd, f"{paths.LINK}/uplink/in_flight")
    assert in_flight.tolist() == [151.0]


def test_ptp_goal_ghost_arm_stands_on_the_newest_base_pose(open_recorder, robot):
    """The ghost starts at the base origin of the newest odometry and ends at the camera of the
    goal configuration there; consecutive points keep the arm's rigid joint offsets."""
    recorder = open_recorder()
    base_position = np.array([0.3, -0.2, 0.1])
    recorder.base_odom(0, base_position, _base_quaternion(500))
    goal = np.radians([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
    recorder.ptp_goal(PERIOD_NS, goal)
    with pytest.raises(InputError, match="finite"):
        recorder.ptp_goal(2 * PERIOD_NS, [math.nan] * 7)
    recorder.ptp_goal(3 * PERIOD_NS, None)  # deploy: no fixed goal
    recorder.close()
    rrd = recorder.sink.rrd_path
    rows = read_components(rrd, paths.PTP_GOAL)
    strips = [row for row in rows if "LineStrips3D:strips" in row]
    assert len(strips) == 1
    points = np.array(strips[0]["LineStrips3D:strips"][0])
    assert points.shape == (robot.n + 2, 3)
    q = robot.configuration(goal, base_position, _base_quaternion(500))
    camera = FreeFloatingState.compute(robot, q).camera.position
    np.testing.assert_allclose(points[0], base_position, atol=1e-6)
    np.testing.assert_allclose(points[-1], camera, atol=1e-6)
    joints = read_components(rrd, paths.PTP_GOAL_JOINTS)
    assert any("Points3D:positions" in row for row in joints)
    # the deploy goal clears the ghost (a Clear tombstone on the entity)
    assert any(any("Clear" in key for key in row) for row in rows)


def test_energy_and_wheel_series_come_back_by_label(open_recorder):
    recorder = open_recorder()
    recorder.energy(0, {**ENERGY, "unknown": 5.0})
    recorder.wheel_state(0, [1.0, 2.0, 3.0], [0.01, 0.0, -0.1])
    with pytest.raises(InputError, match="finite"):
        recorder.energy(PERIOD_NS, {"total": math.nan})
    recorder.close()
    rrd = recorder.sink.rrd_path
    assert read_scalars(rrd, paths.energy_term("total"))[1].tolist() == [2.05]
    assert read_scalars(rrd, paths.energy_lambda("wheels"))[1].tolist() == [40.0]
    assert read_scalars(rrd, paths.energy_cost("c_sum"))[1].tolist() == [12.0]
    assert read_scalars(rrd, paths.WHEEL_SPEED_AXES[2])[1].tolist() == [3.0]
    assert read_scalars(rrd, paths.WHEEL_TORQUE_AXES[2])[1].tolist() == [-0.1]


def test_a_file_cut_short_is_not_a_complete_recording(open_recorder, tmp_path):
    """rrd_problem reads every chunk (as ``rerun rrd verify`` does): a whole file passes, the
    same bytes cut short or missing do not."""
    from rns_ros.viz.readback import rrd_problem

    recorder = open_recorder()
    _feed(recorder, 50)
    recorder.close()
    assert recorder.problem is None
    data = recorder.sink.rrd_path.read_bytes()
    assert rrd_problem(recorder.sink.rrd_path) is None
    cut = tmp_path / "cut.rrd"
    for size in (len(data) - 1, len(data) // 2, len(data) // 3, 100):
        cut.write_bytes(data[:size])
        assert rrd_problem(cut) is not None, size  # mid-frame or at a frame boundary
    assert rrd_problem(tmp_path / "missing.rrd") == "the file does not exist"


def test_a_recording_over_the_file_size_limit_is_said_and_removed(tmp_path):
    """Under ``ulimit -f`` rerun's file writer stops: close() says so, naming the limit, and
    removes the file it could not finish (no exception, no file claimed)."""
    import textwrap

    path = tmp_path / "limited.rrd"
    script = textwrap.dedent(
        f"""
        import numpy as np
        from rns_ros.core import load_model, load_model_config
        from rns_ros.resources import default_model_config
        from rns_ros.viz import RecorderSettings, SinkSettings, TelemetryRecorder
        robot = load_model(default_model_config())
        urdf, _ = load_model_config(default_model_config())
        sink = SinkSettings(kind="save", rrd_path={str(path)!r})
        recorder = TelemetryRecorder(robot, urdf, sink, RecorderSettings())
        theta = np.zeros(7)
        for k in range(20000):
            recorder.joint_state(k * 10_000_000, theta + 1e-4 * k, np.full(7, 0.1))
        recorder.close()
        print(recorder.problem)
        """
    )
    limit = 256 * 1024

    done = run_with_file_size_limit(script, limit, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
    assert done.stdout.strip() == (
        f"cannot write {path}: the file-size limit (ulimit -f) of {limit} bytes was reached; "
        "the file is removed"
    )
    assert not path.exists()
