"""Dense LU factorization with partial pivoting and its solves, for the small (~70 x 70)
systems of the linearly implicit integrators, through LAPACK (``dgetrf``, ``dgetrs``) from
compiled code.

numba's ``np.linalg`` offers ``solve`` and ``inv`` but no separate factorization, and a
Rosenbrock step solves six systems with one matrix. The LAPACK that scipy ships
(``scipy.linalg.cython_lapack``) does the factorization and six solves of a 69 x 69 system in
about half the time of a loop written out in numba (34 us against 71 us on this project's
benchmark machine). Its routines are reached by *name*: their addresses are registered as
symbols with LLVM when this module is imported, so compiled functions that call them can be
cached on disk (a ctypes function pointer cannot be).

LAPACK is column-major, so it sees a C-ordered matrix as its transpose. A caller that stores
A^T (a workspace made with ``transposed=True``, as the integrators do) has ``dgetrf`` factor A
itself and ``dgetrs`` solve A x = b on its untransposed path, a third faster for a 69 x 69
system (1.5 against 2.1 us) than solving with the transpose of the factors of A^T, which is
what a caller storing A gets. Nothing here allocates: the
caller owns every array, and the integer arguments LAPACK reads by address live in the tail of
the pivot array (:func:`lu_workspace`).

The blocked kernels LAPACK runs are chosen for the processor, so the last bits of a
factorization can differ between machines (never between runs on one machine).
"""

from __future__ import annotations

import llvmlite.binding
import numpy as np
from numba import njit, types
from numba.extending import get_cython_function_address

from softcell.settings import JIT

_INT = types.CPointer(types.intc)
_DOUBLE = types.CPointer(types.float64)


def _lapack(name: str, signature) -> types.ExternalFunction:
    symbol = f"softcell_lapack_{name}"
    llvmlite.binding.add_symbol(
        symbol, get_cython_function_address("scipy.linalg.cython_lapack", name)
    )
    return types.ExternalFunction(symbol, signature)


# dgetrf(m, n, a, lda, ipiv, info); dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
_dgetrf = _lapack("dgetrf", types.void(_INT, _INT, _DOUBLE, _INT, _INT, _INT))
_dgetrs = _lapack(
    "dgetrs",
    types.void(types.CPointer(types.int8), _INT, _INT, _DOUBLE, _INT, _INT, _DOUBLE, _INT, _INT),
)

#: Slots of the tail of the pivot array: the order n, one right-hand side, LAPACK's status,
#: and the character 'T' (solve with the transpose of LAPACK's column-major factors).
_N, _NRHS, _INFO, _TRANS = range(4)
_TAIL = 4


def lu_workspace(n: int, transposed: bool = False) -> np.ndarray:
    """The pivot array of an n x n system for :func:`lu_factor` and :func:`lu_solve`:
    int32[n + 4], the row swaps followed by the integer arguments LAPACK reads by address.

    With ``transposed``, the matrix array holds A^T (C order), which LAPACK reads as A
    itself, and the solves run LAPACK's faster untransposed path ('N'); otherwise it holds A
    and the solves run the transposed path ('T')."""
    pivots = np.zeros(n + _TAIL, dtype=np.intc)
    pivots[n + _N] = n
    pivots[n + _NRHS] = 1
    pivots[n + _TRANS] = ord("N" if transposed else "T")
    return pivots


@njit(**JIT)
def holds_transpose(pivots, n):
    """Whether the pivot array ``pivots`` of an n x n system was made by
    :func:`lu_workspace` with ``transposed``: its matrix array then holds A^T."""
    return pivots[n + _TRANS] == ord("N")


@njit(**JIT)
def lu_factor(a, pivots):
    """Factor the square C-contiguous float64 array ``a`` in place (it holds A, or A^T with
    a ``transposed`` workspace; LAPACK factors the transpose of what it holds), recording
    row swaps in ``pivots`` (from :func:`lu_workspace`).

    Returns False if a pivot is exactly zero (a singular matrix), True otherwise.
    """
    n = a.shape[0]
    tail = pivots[n:]
    _dgetrf(
        tail[_N:].ctypes,
        tail[_N:].ctypes,
        a.ctypes,
        tail[_N:].ctypes,
        pivots.ctypes,
        tail[_INFO:].ctypes,
    )
    return tail[_INFO] == 0


@njit(**JIT)
def lu_solve(a, pivots, b):
    """Solve A x = b in place (``b``, float64[n], becomes x) with the factors of
    :func:`lu_factor`, whichever way ``pivots``' workspace says ``a`` held A."""
    n = a.shape[0]
    tail = pivots[n:]
    _dgetrs(
        tail[_TRANS:].view(np.int8).ctypes,
        tail[_N:].ctypes,
        tail[_NRHS:].ctypes,
        a.ctypes,
        tail[_N:].ctypes,
        pivots.ctypes,
        b.ctypes,
        tail[_N:].ctypes,
        tail[_INFO:].ctypes,
    )
