"""The triangular inverse of the compiled kernels (wbmpc/ocp/kernels/linalg.py), written row by row for
speed, against the textbook column-by-column loop it replaced (the test oracle): the same numbers to the
last bit; and the Cholesky factor it inverts (the KKT dynamics and the Riccati pass), against the
textbook loops, with its failures."""

from __future__ import annotations

import numpy as np
import pytest

from wbmpc.ocp.kernels.linalg import cholesky_in_place, lower_triangular_inverse


def _textbook_cholesky(A: np.ndarray) -> bool:
    n = A.shape[0]
    for j in range(n):
        s = A[j, j]
        for p in range(j):
            s -= A[j, p] * A[j, p]
        if not (s > 0.0):
            return False
        d = np.sqrt(s)
        A[j, j] = d
        for i in range(j + 1, n):
            s = A[i, j]
            for p in range(j):
                s -= A[i, p] * A[j, p]
            A[i, j] = s / d
    return True


def _textbook_triangular_inverse(L: np.ndarray) -> np.ndarray:
    n = L.shape[0]
    Linv = np.zeros((n, n))
    for j in range(n):
        Linv[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, n):
            s = 0.0
            for p in range(j, i):
                s -= L[i, p] * Linv[p, j]
            Linv[i, j] = s / L[i, i]
    return Linv


@pytest.mark.parametrize("n", [1, 2, 3, 7, 12, 19, 25, 31])
def test_the_factor_and_its_inverse_are_the_textbook_loops_to_the_last_bit(n):
    rng = np.random.default_rng(n)
    for scale in (1e-6, 1.0, 1e4):
        B = rng.standard_normal((n, n + 3))
        A = scale * (B @ B.T) + 1e-9 * np.eye(n)
        expected = A.copy()
        assert _textbook_cholesky(expected)
        factor = A.copy()
        assert cholesky_in_place(factor)
        assert np.array_equal(np.tril(factor), np.tril(expected))
        assert np.array_equal(np.triu(factor, 1), np.triu(A, 1))  # the upper triangle is left alone
        inverse = np.full((n, n), np.nan)
        lower_triangular_inverse(factor, inverse)
        assert np.array_equal(inverse, _textbook_triangular_inverse(np.tril(factor)))


def test_a_matrix_that_is_not_positive_definite_is_refused():
    rng = np.random.default_rng(0)
    B = rng.standard_normal((6, 6))
    A = B @ B.T
    A[3, 3] = -1.0
    assert not cholesky_in_place(A.copy())
    assert not cholesky_in_place(np.full((2, 2), np.nan))
    assert not cholesky_in_place(np.zeros((3, 3)))
