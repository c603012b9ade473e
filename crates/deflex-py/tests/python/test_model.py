"""deflex.Robot against the independent numpy reference (tests/python/reference.py): forward
kinematics from the DH table, Jacobians by finite differences, J_e K⁻¹ J_eᵀ w; batches equal to
single calls; clear errors for wrong shapes, NaN and wrong types."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import deflex
from reference import ReferenceRobot

W = np.array([120.0, -340.0, -1000.0, 15.0, -8.0, 4.0])


def limits_sample(robot: deflex.Robot, rng: np.random.Generator, n: int) -> np.ndarray:
    lim = robot.limits
    lo = np.where(np.isnan(lim[:, 0]), -np.pi, np.maximum(lim[:, 0], -np.pi))
    hi = np.where(np.isnan(lim[:, 1]), np.pi, np.minimum(lim[:, 1], np.pi))
    return rng.uniform(lo, hi, size=(n, robot.joint_count))


@pytest.mark.parametrize("name", ["tx200", "ur10", "kr210-r2700", "irb4600"])
def test_pose_matches_the_textbook_dh_chain(name: str, rng: np.random.Generator) -> None:
    robot = deflex.Robot.builtin(name)
    ref = ReferenceRobot(name)
    for q in limits_sample(robot, rng, 20):
        np.testing.assert_allclose(robot.pose(q), ref.pose(q), atol=1e-12)


@pytest.mark.parametrize("name", ["tx200", "ur10"])
def test_jacobian_matches_finite_differences(name: str, rng: np.random.Generator) -> None:
    robot = deflex.Robot.builtin(name)
    ref = ReferenceRobot(name)
    for q in limits_sample(robot, rng, 10):
        np.testing.assert_allclose(robot.jacobian(q), ref.jacobian(q), atol=1e-7)


@pytest.mark.parametrize("name", ["tx200", "tx200-1edof", "ur10", "irb4600"])
def test_compliance_and_deflection_match_the_vjm_reference(name: str, rng: np.random.Generator) -> None:
    robot = deflex.Robot.builtin(name)
    ref = ReferenceRobot(name)
    assert robot.edofs == [f"J{i}.{a}" for i, a, _, _ in ref.springs]
    for q in limits_sample(robot, rng, 10):
        c_ref = ref.compliance(q)
        c = robot.compliance(q)
        scale = np.abs(c_ref).max()
        np.testing.assert_allclose(c, c_ref, atol=1e-7 * scale)
        np.testing.assert_allclose(c, c.T, atol=1e-15 * scale)
        d_ref = ref.deflect(q, W)
        np.testing.assert_allclose(robot.deflect(q, W), d_ref, atol=1e-7 * np.abs(d_ref).max())


def test_figure_7_configuration_reproduces_the_readme_numbers() -> None:
    # README: deflex deflect --robot tx200 --q-deg 0,90,0,0,0,0 --wrench 0,1400,0,0,0,0
    robot = deflex.Robot.builtin("tx200")
    q = np.radians([0, 90, 0, 0, 0, 0])
    d = robot.deflect(q, [0, 1400, 0, 0, 0, 0])
    np.testing.assert_allclose(d[:3] * 1e3, [0.3839, 3.8587, 0.0], atol=5e-5)
    np.testing.assert_allclose(d[5] * 1e3, 2.2837, atol=5e-5)
    np.testing.assert_allclose(robot.pose(q)[:3, 3] * 1e3, [2194.0, 0.0, 0.0], atol=5e-4)


def test_batches_equal_single_calls(rng: np.random.Generator) -> None:
    robot = deflex.Robot.builtin("tx200")
    q = limits_sample(robot, rng, 5000)
    wrenches = rng.normal(0, 500, size=(5000, 6))
    batch = robot.deflect(q, W)
    batch_w = robot.deflect(q, wrenches)
    poses = robot.pose(q)
    jac = robot.jacobian(q)
    comp = robot.compliance(q)
    assert batch.shape == (5000, 6) and poses.shape == (5000, 4, 4)
    assert jac.shape == (5000, 6, 6) and comp.shape == (5000, 6, 6)
    for i in list(range(0, 5000, 397)) + [4999]:
        assert np.abs(batch[i] - robot.deflect(q[i], W)).max() <= 1e-12
        assert np.abs(batch_w[i] - robot.deflect(q[i], wrenches[i])).max() <= 1e-12
        assert np.abs(poses[i] - robot.pose(q[i])).max() <= 1e-12
        assert np.abs(jac[i] - robot.jacobian(q[i])).max() <= 1e-12
        assert np.abs(comp[i] - robot.compliance(q[i])).max() <= 1e-12
    # Lists, tuples, integer and Fortran-ordered or strided arrays are accepted.
    np.testing.assert_array_equal(robot.deflect(list(q[0]), tuple(W)), batch[0])
    np.testing.assert_array_equal(robot.deflect(np.asfortranarray(q[:50]), W), batch[:50])
    np.testing.assert_array_equal(robot.deflect(q[::2], W), batch[::2])
    np.testing.assert_array_equal(
        robot.deflect(np.zeros(6, dtype=np.int32), W), robot.deflect(np.zeros(6), W)
    )


def test_ik_returns_to_the_pose_and_batches(rng: np.random.Generator) -> None:
    robot = deflex.Robot.builtin("tx200")
    seed = np.radians([0, 49.7, 89.3, 0, 41, 0])
    q = seed + rng.uniform(-0.2, 0.2, size=(8, 6))
    targets = robot.pose(q)
    solved = robot.ik(targets, seed=q + 0.01)
    np.testing.assert_allclose(robot.pose(solved), targets, atol=1e-8)
    single = robot.ik(targets[3])
    np.testing.assert_allclose(robot.pose(single), targets[3], atol=1e-8)
    far = targets[0].copy()
    far[:3, 3] = [40.0, 0.0, 0.0]
    with pytest.raises(deflex.InputError, match="out of reach"):
        robot.ik(far)
    both = robot.ik(np.stack([targets[0], far]), on_failure="nan")
    assert np.isnan(both[1]).all() and np.isfinite(both[0]).all()
    bad = targets[0].copy()
    bad[0, 0] = 3.0
    with pytest.raises(deflex.InputError, match="not a rotation"):
        robot.ik(bad)


def test_properties_and_files(tmp_path: Path) -> None:
    robot = deflex.Robot.builtin("ur10")
    assert robot.joint_count == 6
    assert robot.joint_names[0] == "shoulder_pan_joint"
    assert robot.limits.shape == (6, 2)
    assert "tx200" in deflex.Robot.builtins()
    sag = robot.gravity_sag(np.zeros(6))
    assert sag is not None and sag.shape == (6,) and abs(sag[2]) > 0
    assert deflex.Robot.builtin("tx200").gravity_sag(np.zeros(6)) is None
    path = tmp_path / "ur10.toml"
    robot.save(path)
    again = deflex.Robot.load(path)
    assert again.geometry_fingerprint == robot.geometry_fingerprint
    np.testing.assert_array_equal(again.stiffness, robot.stiffness)
    text = deflex.Robot.from_toml(robot.to_toml(), origin="text")
    assert text.name == robot.name


def test_a_urdf_based_robot_file_loads_and_matches_its_dh_twin(tmp_path: Path) -> None:
    # The TX200's modified DH rows as URDF joint origins: RotX(α)·TransX(a)·TransZ(d)·RotZ(θ0).
    ref = ReferenceRobot("tx200")
    joints, links = "", '<link name="base"/>'
    for i, row in enumerate(ref.rows, start=1):
        alpha, a, d, off = row["alpha"], row["a"], row["d"], row.get("theta_offset", 0.0)
        xyz = (float(a), float(-d * np.sin(alpha)), float(d * np.cos(alpha)))
        parent = "base" if i == 1 else f"link{i - 1}"
        # RotX(α)·RotZ(θ0) as roll-pitch-yaw: roll α about x, then yaw θ0 about the new z ⇒
        # R = Rx(α) Rz(θ0); give it as a fixed-axis rpy via its matrix.
        r = np.array([[np.cos(off), -np.sin(off), 0], [np.sin(off), np.cos(off), 0], [0, 0, 1]])
        rx = np.array([[1, 0, 0], [0, np.cos(alpha), -np.sin(alpha)], [0, np.sin(alpha), np.cos(alpha)]])
        m = rx @ r
        pitch = float(-np.arcsin(np.clip(m[2, 0], -1, 1)))
        roll = float(np.arctan2(m[2, 1], m[2, 2]))
        yaw = float(np.arctan2(m[1, 0], m[0, 0]))
        joints += (
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="link{i}"/>'
            f'<origin xyz="{xyz[0]!r} {xyz[1]!r} {xyz[2]!r}" rpy="{roll!r} {pitch!r} {yaw!r}"/>'
            '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        )
        links += f'<link name="link{i}"/>'
    (tmp_path / "arm.urdf").write_text(f'<robot name="arm">{links}{joints}</robot>')
    toml = 'name = "urdf arm"\nurdf = "arm.urdf"\n' + "".join(
        f'[[joint]]\nname = "j{i}"\nstiffness = {{ z = 1.0e6 }}\n' for i in range(1, 7)
    )
    (tmp_path / "arm.toml").write_text(toml)
    robot = deflex.Robot.load(tmp_path / "arm.toml")
    assert robot.joint_names == [f"j{i}" for i in range(1, 7)]
    q = np.array([0.3, -0.5, 1.1, 0.7, -0.4, 2.0])
    np.testing.assert_allclose(robot.pose(q), ref.pose(q), atol=1e-9)


def test_wrong_shapes_nan_and_types_raise_clear_errors() -> None:
    robot = deflex.Robot.builtin("tx200")
    q = np.zeros(6)
    with pytest.raises(deflex.InputError, match=r"q: expected shape \(6,\) or \(N, 6\).*got \(5,\)"):
        robot.deflect(np.zeros(5), W)
    with pytest.raises(deflex.InputError, match=r"got \(2, 7\)"):
        robot.pose(np.zeros((2, 7)))
    with pytest.raises(deflex.InputError, match=r"got \(0, 6\)"):
        robot.pose(np.zeros((0, 6)))
    with pytest.raises(deflex.InputError, match=r"wrench: expected shape"):
        robot.deflect(q, np.zeros(5))
    with pytest.raises(deflex.InputError, match=r"wrench: .*to match q"):
        robot.deflect(np.zeros((3, 6)), np.zeros((4, 6)))
    with pytest.raises(deflex.InputError, match=r"q\[1, 3\] is NaN"):
        robot.deflect(np.array([q, [0, 0, 0, np.nan, 0, 0]]), W)
    with pytest.raises(deflex.InputError, match=r"wrench\[2\] is inf"):
        robot.deflect(q, [0, 0, np.inf, 0, 0, 0])
    with pytest.raises(deflex.InputTypeError, match="q: expected an array of numbers.*got str"):
        robot.pose("0,0,0,0,0,0")
    with pytest.raises(TypeError, match="got NoneType"):
        robot.compliance(None)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        robot.deflect(q, ["a"] * 6)
    with pytest.raises(deflex.InputError, match="on_failure"):
        robot.ik(np.eye(4), on_failure="ignore")  # type: ignore[arg-type]
    with pytest.raises(deflex.InputError, match="not a built-in robot"):
        deflex.Robot.builtin("tx201")
    with pytest.raises(deflex.ModelError, match="cannot read file"):
        deflex.Robot.load("/nonexistent/robot.toml")
    with pytest.raises(deflex.ModelError, match=r"bad\.toml.*stiffness"):
        deflex.Robot.from_toml('name = "x"\n[[joint]]\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta_offset = 0.0\nstiffness = { z = -1.0 }\n', origin="bad.toml")


def test_the_error_hierarchy() -> None:
    for cls in [
        deflex.InputError,
        deflex.ModelError,
        deflex.DataError,
        deflex.CalibrationError,
        deflex.CompensationError,
        deflex.ProgramError,
        deflex.SimulationError,
        deflex.DeflexIOError,
        deflex.InternalError,
    ]:
        assert issubclass(cls, deflex.DeflexError)
    assert issubclass(deflex.InputError, ValueError)
    assert issubclass(deflex.InputTypeError, TypeError)


def test_threads_share_the_robot_and_release_the_gil(rng: np.random.Generator) -> None:
    from concurrent.futures import ThreadPoolExecutor

    robot = deflex.Robot.builtin("tx200")
    q = limits_sample(robot, rng, 20000)
    expected = robot.deflect(q, W)
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda k: robot.deflect(q, W * 1.0), range(8)))
    for r in results:
        np.testing.assert_array_equal(r, expected)
