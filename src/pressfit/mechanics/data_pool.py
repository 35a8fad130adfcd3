"""Pinocchio ``Data`` lent to the models' users and taken back, instead of created for each of them.

A ``pin.Data`` carries, besides a model's kinematic and dynamic quantities, Pinocchio's second-order derivative
tensors (nv^3 doubles each): for the 122-velocity elastic VJM model of :mod:`pressfit.mechanics.model` it is
67 MB, and creating one costs 15-60 ms (zeroing it and faulting its fresh pages in), several times a static
solve (about 9 ms). A solver, a flexible machine or a reduced system built per call (``solve_equilibrium`` on a
machine, a study's pose) paid that every time: a third of the test suite's CPU.

:func:`lend` hands a Data to a model object for its lifetime and takes it back when that object is garbage
collected (``weakref.finalize``), so no two holders use one Data at once; :func:`borrowed` lends one for a
``with`` block. A Data is only lent for a model of the same structure as the one it was made for (the joints'
types and parents, nq, nv and the frames: all a Data's layout depends on), and every algorithm writes what it
computes before it is read, so a lent Data gives the same results, bit for bit, as a fresh one
(tests/mechanics/test_data_pool.py). Idle Data are kept per process (under a lock: a Dask worker's threads share
them, and its memory is bounded whatever their number), the most recently returned first, up to ``IDLE_BYTES`` in
all (four of the elastic model's); a forked child starts with none. A model with fewer than ``POOLED_NV``
velocities creates its own (microseconds).
"""

from __future__ import annotations

import collections
import os
import threading
import weakref
from collections.abc import Iterator
from contextlib import contextmanager

import pinocchio as pin

IDLE_BYTES = 300e6  # idle Data kept per process, at most this much in all (estimated by data_bytes)
POOLED_NV = 40  # models with fewer velocities (the rigid-leg model: 26) create their own Data


class _Idle:
    def __init__(self) -> None:
        self.data: list[tuple[tuple, pin.Data]] = []  # (structure, Data), the most recently returned last; locked
        # given back without the lock (a finalizer may run inside a locked region, where an allocation started a
        # garbage collection): moved into ``data`` by whoever holds the lock next
        self.returned: collections.deque[tuple[tuple, pin.Data]] = collections.deque()
        self.lock = threading.Lock()

    def settle(self) -> None:
        """The returned Data into the idle list, the oldest beyond IDLE_BYTES dropped (the lock held)."""
        while self.returned:
            self.data.append(self.returned.popleft())
        total = 0.0
        for k in range(len(self.data) - 1, -1, -1):  # the most recently returned first
            total += data_bytes(self.data[k][0][1])
            if total > IDLE_BYTES:
                del self.data[: k + 1]
                break


_IDLE = _Idle()
os.register_at_fork(after_in_child=_IDLE.__init__)  # a child's own empty pool and a lock no thread holds


def structure(model: pin.Model) -> tuple:
    """What a Data's layout depends on: nq, nv, the frames' count and the joints' types and parents."""
    return (model.nq, model.nv, model.nframes, tuple(j.shortname() for j in model.joints), tuple(model.parents))


def _take(model: pin.Model) -> tuple[tuple | None, pin.Data]:
    if model.nv < POOLED_NV:
        return None, model.createData()
    key, idle = structure(model), _IDLE.data
    with _IDLE.lock:
        _IDLE.settle()
        for i in range(len(idle) - 1, -1, -1):
            if idle[i][0] == key:
                return key, idle.pop(i)[1]
    return key, model.createData()


def data_bytes(nv: int) -> float:
    """A Data's size (bytes) for nv velocities: four nv^3 tensors of doubles and the rest (measured 66.6 MB at
    nv = 122, 36 nv^3)."""
    return 36.0 * nv**3


def _give_back(key: tuple | None, data: pin.Data) -> None:
    if key is not None:
        _IDLE.returned.append((key, data))
        if _IDLE.lock.acquire(blocking=False):  # held (here, by a collection inside _take): the holder settles it
            try:
                _IDLE.settle()
            finally:
                _IDLE.lock.release()


def lend(model: pin.Model, owner: object | None = None) -> pin.Data:
    """A Data for ``model``, ``owner``'s alone until ``owner`` is garbage collected (then idle again); by default
    the model object's own: the pairing every holder of a model and its Data has (a solver's model copy, a flexible
    machine's model). A holder of a model it shares with others (an evaluator of an interference model) is the
    owner itself."""
    key, data = _take(model)
    weakref.finalize(model if owner is None else owner, _give_back, key, data).atexit = False
    return data


@contextmanager
def borrowed(model: pin.Model) -> Iterator[pin.Data]:
    """A Data for ``model`` for the ``with`` block (idle again after it: keep nothing that views it)."""
    key, data = _take(model)
    try:
        yield data
    finally:
        _give_back(key, data)
