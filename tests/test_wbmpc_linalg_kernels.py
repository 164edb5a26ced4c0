"""The triangular inverse of the compiled kernels (wbmpc/ocp/kernels/linalg.py), written row by row for
speed, against the textbook column-by-column loop it replaced (the test oracle): the same numbers to the
last bit; and the Cholesky factor it inverts (the KKT dynamics and the Riccati pass), against LAPACK's
(numpy.linalg.cholesky) to rounding, with its failures."""

from __future__ import annotations

import numpy as np
import pytest

from wbmpc.ocp.kernels.linalg import cholesky_in_place, lower_triangular_inverse


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
def test_the_factor_is_lapacks_and_its_inverse_the_textbook_loop_to_the_last_bit(n):
    rng = np.random.default_rng(n)
    for scale in (1e-6, 1.0, 1e4):
        B = rng.standard_normal((n, n + 3))
        A = scale * (B @ B.T) + 1e-9 * np.eye(n)
        factor = A.copy()
        assert cholesky_in_place(factor)
        expected = np.linalg.cholesky(A)
        np.testing.assert_allclose(np.tril(factor), expected, rtol=0.0, atol=1e-12 * np.abs(expected).max())
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
