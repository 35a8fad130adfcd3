"""Pinocchio Data lent and taken back (:mod:`pressfit.mechanics.data_pool`): never shared by two live holders,
only between models of one structure, and a lent Data gives the results of a fresh one bit for bit."""

import numpy as np
import pytest

from pressfit.dynamics.modes import natural_modes
from pressfit.mechanics import data_pool
from pressfit.mechanics.model import build_model
from pressfit.mechanics.statics import EquilibriumSolver, solve_equilibrium

POSE_A, POSE_B = np.array([0.0, 0.72, 0.0]), np.array([0.12, 0.6, -0.08])
LOAD = np.array([40.0, -700.0, 25.0, 3.0, -2.0, 1.0])


@pytest.fixture
def empty_pool():
    """The calling thread's idle Data cleared before and after the test (a model no longer referenced gives its
    Data back at once: reference counting, no cycle collection needed)."""
    data_pool._IDLE.data.clear()
    yield data_pool._IDLE.data
    data_pool._IDLE.data.clear()


def test_a_holder_keeps_its_data_until_it_is_collected_and_the_next_one_gets_it(machine, empty_pool):
    """Two live models of one structure hold two Data; when one is collected its Data is idle, and the next model
    of that structure is lent that very object; a model of another structure (Tsai's 3-UPU) is not."""
    first, second = build_model(machine, POSE_A).model, build_model(machine, POSE_B).model
    a, b = data_pool.lend(first), data_pool.lend(second)
    assert a is not b and not empty_pool
    del first
    assert [d for _, d in empty_pool] == [a]
    assert data_pool.lend(build_model(machine, POSE_B).model) is a


def test_another_structure_never_gets_the_data(machine, tsai, empty_pool):
    """An idle Data of the 4-UPU's model is not lent to Tsai's (other joints, other nv), nor to the 4-UPU's with
    another number of springs per segment."""
    model = build_model(machine, POSE_A).model
    lent = data_pool.lend(model)
    del model
    others = build_model(tsai, POSE_A).model, build_model(machine, POSE_A, springs_per_segment=3).model
    assert all(data_pool.lend(m) is not lent for m in others)
    assert [d for _, d in empty_pool] == [lent]  # still idle


def test_a_borrowed_data_is_idle_again_after_the_block_even_on_an_error(machine, empty_pool):
    model = build_model(machine, POSE_A).model
    with pytest.raises(RuntimeError), data_pool.borrowed(model) as data:
        raise RuntimeError("inside")
    assert [d for _, d in empty_pool] == [data]
    with data_pool.borrowed(model) as again:
        assert again is data and not empty_pool


def test_idle_data_are_kept_up_to_their_byte_budget(machine, empty_pool, monkeypatch):
    """With room for exactly two of the elastic model's Data (its estimated size times 2.5), five returned leave the
    last two idle; the estimate is within 10% of the measured 66.6 MB at nv = 122."""
    models = [build_model(machine, POSE_A).model for _ in range(5)]
    assert data_pool.data_bytes(models[0].nv) == pytest.approx(66.6e6, rel=0.1)
    monkeypatch.setattr(data_pool, "IDLE_BYTES", 2.5 * data_pool.data_bytes(models[0].nv))
    lent = [data_pool.lend(m) for m in models]
    del models
    assert [d for _, d in empty_pool] == lent[-2:]


def test_a_lent_data_gives_a_fresh_ones_results_bit_for_bit(machine, empty_pool, monkeypatch):
    """A solve and the natural modes at pose A on Data that served a solve at pose B (another stem placement, another
    load) and the electric machine's modes (other masses, the drives' armature on the actuators) equal those on
    fresh Data (the pool bypassed: every model below its threshold), bit for bit."""
    from pathlib import Path

    from pressfit.description.machine import load_machine

    electric = load_machine(Path(__file__).resolve().parents[2] / "models" / "pressfit_4upu_electric.toml")
    assert data_pool.structure(build_model(electric, POSE_B).model) == data_pool.structure(
        build_model(machine, POSE_A).model)
    solve_equilibrium(machine, POSE_B, -LOAD)
    natural_modes(electric, POSE_B)  # the same structure with other masses and the drives' armature
    assert empty_pool  # the next solve and modes are lent what those used
    lent = solve_equilibrium(machine, POSE_A, LOAD), natural_modes(machine, POSE_A)
    monkeypatch.setattr(data_pool, "POOLED_NV", 10**9)
    fresh = solve_equilibrium(machine, POSE_A, LOAD), natural_modes(machine, POSE_A)
    assert np.array_equal(lent[0].q, fresh[0].q)
    assert np.array_equal(lent[0].actuator_forces_n, fresh[0].actuator_forces_n)
    assert np.array_equal(lent[1].frequencies_hz, fresh[1].frequencies_hz)
    assert np.array_equal(lent[1].shapes, fresh[1].shapes)


def test_a_solver_per_call_no_longer_creates_a_data_per_call(machine, empty_pool, monkeypatch):
    """Ten solves, each on a new solver (as ``solve_equilibrium`` on a machine does): one Data created (each
    solver's is idle again when the solver goes), not ten."""
    created = []
    real = data_pool._take

    def counting(model):
        key, data = real(model)
        if not any(data is d for d in created):
            created.append(data)
        return key, data

    monkeypatch.setattr(data_pool, "_take", counting)
    for k in range(10):
        EquilibriumSolver(build_model(machine, POSE_A)).solve(POSE_A, LOAD * (1 + k / 10))
    assert len(created) == 1


def test_the_structure_tells_apart_parents_and_frames():
    """Two models with the same joints but another topology (a chain against two branches), or another frame
    count, have another structure: a Data is never lent across them."""
    import pinocchio as pin

    def model(chain: bool, frames: int = 0):
        m = pin.Model()
        a = m.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "a")
        m.addJoint(a if chain else 0, pin.JointModelRY(), pin.SE3.Identity(), "b")
        for k in range(frames):
            m.addFrame(pin.Frame(f"f{k}", a, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
        return m

    assert data_pool.structure(model(True)) == data_pool.structure(model(True))
    assert data_pool.structure(model(True)) != data_pool.structure(model(False))
    assert data_pool.structure(model(True)) != data_pool.structure(model(True, frames=1))


def test_a_holder_of_a_shared_model_is_the_owner(machine, empty_pool):
    """Two evaluators of one shared model (an interference model's rig) each hold their own Data, given back when
    that evaluator goes, not when the shared model does."""

    class Holder:
        pass

    model = build_model(machine, POSE_A).model
    first, second = Holder(), Holder()
    a, b = data_pool.lend(model, first), data_pool.lend(model, second)
    assert a is not b
    del first
    assert [d for _, d in empty_pool] == [a]
    del second
    assert [d for _, d in empty_pool] == [a, b]
    assert model.nv == 122  # the shared model still alive


def test_a_data_given_back_while_the_lock_is_held_waits_and_is_lent_next(machine, empty_pool):
    """A holder collected while the pool's lock is held (a garbage collection started by an allocation inside a
    locked region runs its finalizer there): the Data waits in the returned queue, no deadlock, and the next take
    settles and lends it."""
    model = build_model(machine, POSE_A).model
    lent = data_pool.lend(model)
    with data_pool._IDLE.lock:
        del model
        assert not empty_pool and list(data_pool._IDLE.returned) == [(data_pool.structure(
            build_model(machine, POSE_A).model), lent)]
    assert data_pool.lend(build_model(machine, POSE_B).model) is lent
    assert not data_pool._IDLE.returned


def test_threads_share_the_idle_data_and_a_forked_child_starts_empty(machine, empty_pool):
    """A Data given back on one thread is lent on another (one pool per process: its memory bounded whatever the
    number of a Dask worker's threads); a child forked with idle Data in the parent starts with none."""
    import multiprocessing
    import threading

    model = build_model(machine, POSE_A).model
    lent = data_pool.lend(model)
    del model
    assert [d for _, d in empty_pool] == [lent]
    got = []
    thread = threading.Thread(target=lambda: got.append(data_pool.lend(build_model(machine, POSE_B).model)))
    thread.start()
    thread.join()
    assert got == [lent]
    got.clear()  # its model died with the thread's lambda: the Data is idle again
    assert [d for _, d in empty_pool] == [lent]
    with multiprocessing.get_context("fork").Pool(1) as pool:
        assert pool.apply(_idle_count) == 0


def _idle_count() -> int:
    return len(data_pool._IDLE.data) + len(data_pool._IDLE.returned)
