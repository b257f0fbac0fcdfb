"""The LMPC's QP min ½ zᵀHz + fᵀz, lb ≤ z ≤ ub, lba ≤ Az ≤ uba, through CasADi's conic interface (eq. 25).

Paper 001 solves its condensed LMPC problem with qpOASES; CasADi ships qpOASES (and DAQP, OSQP, HiGHS) as
``conic`` plugins, so the QP is handed to a maintained solver rather than a hand-written one. The
Hessian and the constraint matrix are constant for a linear MPC, so they are given once; each call passes
f and the bounds.

qpOASES (LGPL-2.1, shipped inside CasADi) prints its licence banner on stdout every time a solver is
built; that output is discarded so it never mixes with a command's JSON or tables.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np

from planner.errors import InvalidInput

QP_SOLVERS = ("qpoases", "daqp", "osqp")


@contextlib.contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence stdout while a solver prints its banner: CasADi forwards C++ output to Python's
    ``sys.stdout`` (caught by ``redirect_stdout``), anything written to descriptor 1 directly goes to
    /dev/null; both are restored afterwards."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        with contextlib.redirect_stdout(io.StringIO()):
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


class DenseQP:
    """A QP with fixed H and A, solved by a CasADi conic plugin (``qpoases`` by default)."""

    def __init__(self, hessian: np.ndarray, a: np.ndarray | None = None, solver: str = "qpoases") -> None:
        from planner.extras import require

        ca = require("casadi", "qpsol", "the pendulum controllers' QP solver")
        if solver not in QP_SOLVERS:
            raise InvalidInput("qpsol", f"must be one of {', '.join(QP_SOLVERS)}, got {solver!r}")
        h = np.asarray(hessian, dtype=float)
        if h.ndim != 2 or h.shape[0] != h.shape[1]:
            raise InvalidInput("hessian", f"must be square, got shape {h.shape}")
        self.n = h.shape[0]
        self.solver_name = solver
        self._h = ca.DM(0.5 * (h + h.T))
        a_mat = np.zeros((0, self.n)) if a is None else np.asarray(a, dtype=float)
        if a_mat.ndim != 2 or a_mat.shape[1] != self.n:
            raise InvalidInput("a", f"must have {self.n} columns, got shape {a_mat.shape}")
        self.m = a_mat.shape[0]
        self._a = ca.DM(a_mat)
        opts: dict[str, Any] = {"error_on_fail": False}
        if solver == "qpoases":
            opts.update({"printLevel": "none", "sparse": False})
        elif solver == "osqp":
            opts.update({"osqp": {"verbose": False, "eps_abs": 1e-6, "eps_rel": 1e-6, "polish": True}})
        a_sp = ca.Sparsity.dense(self.m, self.n) if self.m else ca.Sparsity(0, self.n)
        with _quiet_stdout():
            self._qp = ca.conic("lmpc_qp", solver, {"h": ca.Sparsity.dense(self.n, self.n), "a": a_sp}, opts)
        self.last_ok = True

    def solve(
        self,
        f: np.ndarray,
        lb: np.ndarray,
        ub: np.ndarray,
        lba: np.ndarray | None = None,
        uba: np.ndarray | None = None,
    ) -> np.ndarray:
        """The minimiser z (n,); :attr:`last_ok` says whether the solver reported success."""
        args: dict[str, Any] = {
            "h": self._h,
            "g": np.asarray(f, float),
            "lbx": np.asarray(lb, float),
            "ubx": np.asarray(ub, float),
        }
        if self.m:
            args.update(a=self._a, lba=np.asarray(lba, float), uba=np.asarray(uba, float))
        sol = self._qp(**args)
        self.last_ok = bool(self._qp.stats()["success"])
        z = np.asarray(sol["x"]).ravel()
        return np.clip(z, lb, ub)


__all__ = ["QP_SOLVERS", "DenseQP"]
