r"""Motion/force scenario files (``config/scenarios/*.yaml`` with ``kind: motion_force``).

One file holds one chapter-6 task of :mod:`rns_ros.control.contact_tasks` as YAML, so that the
DDS stack (``rns_operator`` -> ``rns_force_controller`` -> ``rns_simulator``) and the in-process
reproduction play the same task. Keys, and what the operator publishes (:func:`operator_sample`):
docs/part2_ros.md.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from rns_ros.control.contact_tasks import ArcScenario, Setup, WallScenario
from rns_ros.control.scenario import Scenario, load_scenario
from rns_ros.core.config import check_keys, read_yaml_mapping
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.validation import Choice, short_repr

#: Scenario-file key naming its kind; absent = :attr:`ScenarioKind.CAMERA_ROTATION` (Part I).
KIND_KEY = "kind"
#: Keys every Part II file may hold besides the task's dataclass fields.
_COMMON_KEYS = {KIND_KEY, "task", "name", "description"}


class ScenarioKind(Choice):
    """What a scenario file commands."""

    __label__ = "scenario kind"
    CAMERA_ROTATION = "camera_rotation"  # Part I: a camera angular velocity (control.scenario)
    MOTION_FORCE = "motion_force"  # Part II: EE motion along a surface + a normal force


class Task(Choice):
    """The chapter-6 task of a motion/force scenario."""

    __label__ = "motion_force task"
    WALL = "wall"  # WallScenario, thesis section 6.2.2 (Figs. 6.7-6.8)
    ARC = "arc"  # ArcScenario, thesis section 6.2.1 (Figs. 6.3-6.4)


#: Task -> its dataclass.
TASK_CLASSES: dict[Task, type[ArcScenario] | type[WallScenario]] = {
    Task.WALL: WallScenario,
    Task.ARC: ArcScenario,
}


@dataclass(frozen=True)
class MotionForceScenario:
    """One loaded Part II scenario file.

    Attributes:
        name: identifier (the file stem unless ``name`` is given).
        task: :class:`Task`.
        spec: the analysis dataclass (compares equal to ``WallScenario()`` / ``ArcScenario()``
            when the file holds the defaults).
        setup: ``spec.setup()``: the task resolved on its arm (start configuration, reference,
            f_des, constraint). Not compared.
        description: free text.
    """

    name: str
    task: Task
    spec: ArcScenario | WallScenario
    setup: Setup = field(repr=False, compare=False)
    description: str = ""

    @property
    def duration(self) -> float:
        """Motion profile length [s] (the force is held at ``spec.force`` after it)."""
        return self.spec.duration


class OperatorSample(NamedTuple):
    """What the operator publishes at one profile time (world axes).

    Attributes:
        linear: EE reference velocity p_dot_des [m/s] (3,).
        angular: EE angular velocity [rad/s] (3,), zeros (orientation held or free).
        force: desired normal force f_des >= 0 [N].
        normal: unit contact normal into the environment at p_des (3,).
    """

    linear: np.ndarray
    angular: np.ndarray
    force: float
    normal: np.ndarray

    @property
    def force_vector(self) -> np.ndarray:
        """f_des n: the force the EE should exert on the environment [N] (3,)."""
        return self.force * self.normal


def operator_sample(setup: Setup, t: float) -> OperatorSample:
    """Reference twist and force setpoint of ``setup`` at profile time ``t`` [s].

    Before 0 the references are at rest at the start with f_des = 0; after ``setup.duration``
    the velocity is 0 and the force holds its last value (the quintics are clamped).

    Raises:
        InputError: a non-finite ``t`` or sample (never published), or a reference point
            without a contact normal (on the arc axis).
    """
    t = float(t)
    if not np.isfinite(t):
        raise InputError(f"profile time must be finite [s], got {t!r}")
    reference = setup.reference(t)
    normal = np.asarray(setup.constraint.gradient(reference.position), dtype=float)
    sample = OperatorSample(
        np.array(reference.velocity, dtype=float),
        np.zeros(3),
        float(setup.force(t)),
        normal,
    )
    if not (
        np.isfinite(sample.linear).all() and np.isfinite(sample.force) and np.isfinite(normal).all()
    ):
        raise InputError(f"non-finite operator sample at t = {t} s: {sample}")
    return sample


def scenario_kind(path: str | Path) -> ScenarioKind:
    """The :class:`ScenarioKind` of a scenario file (its ``kind`` key, default camera_rotation).

    Raises:
        ConfigError: missing file, invalid YAML, not a mapping, or an unknown kind.
    """
    path, content = _read(path)
    try:
        return ScenarioKind.parse(content.get(KIND_KEY, ScenarioKind.CAMERA_ROTATION.value))
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def load_motion_force_scenario(path: str | Path) -> MotionForceScenario:
    """Read, validate and resolve a ``kind: motion_force`` scenario file (module docstring).

    Raises:
        ConfigError: naming the file and the bad key or value (unknown key, wrong kind or task,
            a value out of the dataclass' range, a direction along the wall normal, an
            unreachable arc start, a missing model file).
    """
    path, content = _read(path)
    where = str(path)
    kind = content.get(KIND_KEY)
    if kind is None:
        raise ConfigError(
            f"{where}: missing key 'kind' (a motion/force scenario says kind: motion_force)"
        )
    try:
        if ScenarioKind.parse(kind) is not ScenarioKind.MOTION_FORCE:
            raise ConfigError(f"kind must be {ScenarioKind.MOTION_FORCE.value!r}, got {kind!r}")
        if "task" not in content:
            raise ConfigError(f"missing key 'task' (one of {[t.value for t in Task]})")
        task = Task.parse(content["task"])
        cls = TASK_CLASSES[task]
        fields = {f.name for f in dataclasses.fields(cls)}
        check_keys(content, _COMMON_KEYS | fields, f"task {task.value}")
        values = {key: content[key] for key in fields if key in content}
        _check_types(values)
        spec = cls(**values)
        setup = spec.setup()
    except (ConfigError, InputError, TypeError, ValueError) as exc:
        raise ConfigError(f"{where}: {exc}") from None
    return MotionForceScenario(
        name=str(content.get("name", path.stem)),
        task=task,
        spec=spec,
        setup=setup,
        description=str(content.get("description", "")),
    )


def load_contact_scenario(path: str | Path) -> ArcScenario | WallScenario:
    """The task of a ``kind: motion_force`` file as its analysis dataclass (``.setup()``,
    ``.duration``, :func:`~rns_ros.analysis.motion_force_runs.run_closed_loop` take it as it is).

    Raises:
        ConfigError: as :func:`load_motion_force_scenario`.
    """
    return load_motion_force_scenario(path).spec


def load_operator_scenario(path: str | Path) -> Scenario | MotionForceScenario:
    """A scenario file of either kind: Part I :class:`~rns_ros.control.scenario.Scenario`
    (no ``kind`` key) or :class:`MotionForceScenario` (``kind: motion_force``).

    Raises:
        ConfigError: as :func:`scenario_kind` and the loader of that kind.
    """
    if scenario_kind(path) is ScenarioKind.MOTION_FORCE:
        return load_motion_force_scenario(path)
    return load_scenario(path)


def _read(path: str | Path) -> tuple[Path, dict]:
    """(path, mapping) of a YAML file holding one mapping; keys are checked per kind and task."""
    return read_yaml_mapping(path, None, "scenario file")


def _check_types(values: dict) -> None:
    """YAML types the dataclasses do not check themselves (they coerce with float())."""
    for key in ("model",):
        if key in values and not isinstance(values[key], str):
            raise ConfigError(
                f"{key} must be a model file name in config/, got {short_repr(values[key])}"
            )
    if "centripetal" in values and not isinstance(values["centripetal"], bool):
        raise ConfigError(
            f"centripetal must be true or false, got {short_repr(values['centripetal'])}"
        )
    for key, value in values.items():
        if isinstance(value, bool) and key != "centripetal":
            raise ConfigError(f"{key} must be a number, got {short_repr(value)}")
        if isinstance(value, str) and key != "model":
            raise ConfigError(
                f"{key} must be a number or a list of numbers, got {short_repr(value)}"
            )


__all__ = [
    "KIND_KEY",
    "TASK_CLASSES",
    "MotionForceScenario",
    "OperatorSample",
    "ScenarioKind",
    "Task",
    "load_contact_scenario",
    "load_motion_force_scenario",
    "load_operator_scenario",
    "operator_sample",
    "scenario_kind",
]
