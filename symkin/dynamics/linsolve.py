"""Straight-line linear solves for generated code (forward dynamics, J^-T, operational space).

Generated code must run without branches or library calls, so every solve here is a fixed
sequence of arithmetic on *named* entries (:meth:`Program.let`): the matrix entries stand
for their (large) expressions once, every factor is computed once, and CSE shares the rest.

* :func:`ldl_solve` - ``A X = B`` for symmetric positive definite A (the mass matrix) by
  A = L D L^T without pivoting.  For an SPD matrix every pivot D_k is positive (Golub &
  Van Loan, *Matrix Computations*, sec. 4.1-4.2), so the factorization exists and is
  backward stable without pivoting; it costs n^3/6 multiplications and no square roots.
* :func:`ldl_substitution_map` - the substitutions with given factors as one body for many right-hand sides
  (a column map, :class:`~symkin.ir.spec.ColumnMap`): a loop in the backends that have loops.
* :func:`transpose_solve` - ``J^T X = B`` for a square, nonsingular but otherwise general
  matrix (a task Jacobian).  Elimination without pivoting is not sound here: a leading
  minor of J may vanish where J is regular (the UR10e at q = 0 has J_11 = 0), and dividing
  by it gives NaN.  Two sound straight-line methods are used instead:

  - m <= 3: the adjugate, J^-T = cof(J) / det(J) - exact closed forms (the seed writes J^-T
    of the planar arm this way, sec. 4.4.1) that fail only where det J = 0, i.e. at the
    singularities where no J^-T exists;
  - m > 3: J^T = U T by modified Gram-Schmidt with the right-hand sides carried along as
    extra columns (Bjorck, *Numerical Methods for Least Squares Problems*, sec. 2.4.3), in
    its square-root-free form: the columns u_k of U are the successive orthogonal residuals
    themselves, not normalized, and T is unit upper triangular with t_kj = u_k . a_j / d_k,
    d_k = |u_k|^2 (the QR factors are Q = U D^-1/2, R = D^1/2 T).  d_k > 0 for every
    nonsingular J, the augmented form is backward stable for the solution as the normalized
    one is (normalizing scales each residual, which rounding sees only as relative errors of
    the same order), and the formula stays rational in J's entries: no square roots for the
    generated code to take and none for the exact elimination of the base parameters to
    carry (:mod:`symkin.parallel.base_parameters`).

All functions take and return SymEngine expressions.
"""

from __future__ import annotations

import symengine as se

from symkin.dynamics.program import Program, ProgramMap, dot
from symkin.ir.spec import MAP_COLUMN_PREFIX, MAP_SHARED_PREFIX

Matrix = list[list[se.Basic]]

#: Largest size solved by the adjugate (closed form); larger systems use Gram-Schmidt QR.
ADJUGATE_MAX_SIZE = 3


def ldl_factor(program: Program, A: Matrix) -> tuple[Matrix, list[se.Basic]]:
    """(L, D) of A = L D L^T, L unit lower triangular (its entries below the diagonal named, the rest 0), for
    symmetric positive definite A (n x n); only the lower triangle of A is used.  Every entry is named in
    ``program``; solve with the factors by :func:`ldl_substitute` and :func:`ldl_substitution_map`."""
    n = len(A)
    A = [[program.let(A[i][j]) for j in range(i + 1)] for i in range(n)]
    D: list[se.Basic] = []
    L: Matrix = [[se.Integer(0)] * n for _ in range(n)]
    # E[i][k] = L[i][k] * D[k], kept to save a multiplication per use.
    E: Matrix = [[se.Integer(0)] * n for _ in range(n)]
    for j in range(n):
        D.append(program.let(A[j][j] - sum((L[j][k] * E[j][k] for k in range(j)), se.Integer(0))))
        inverse = program.let(1 / D[j])
        for i in range(j + 1, n):
            E[i][j] = program.let(A[i][j] - sum((L[i][k] * E[j][k] for k in range(j)), se.Integer(0)))
            L[i][j] = program.let(E[i][j] * inverse)
    return L, D


def ldl_solve(program: Program, A: Matrix, B: Matrix) -> Matrix:
    """X with A X = B, for symmetric positive definite A (n x n) and B (n x r), by LDL^T (:func:`ldl_factor`).

    Only the lower triangle of A is used.
    """
    return ldl_substitute(program, *ldl_factor(program, A), B)


def ldl_substitute(program: Program, L: Matrix, D: list[se.Basic], B: Matrix) -> Matrix:
    """X with L D L^T X = B for the factors of :func:`ldl_factor` and B (n x r): L y = b, then D L^T x = y."""
    n = len(L)
    columns = []
    for c in range(len(B[0])):
        y: list[se.Basic] = []
        for i in range(n):  # L y = b
            y.append(program.let(B[i][c] - sum((L[i][k] * y[k] for k in range(i)), se.Integer(0))))
        x: list[se.Basic] = [se.Integer(0)] * n
        for i in reversed(range(n)):  # D L^T x = y
            x[i] = program.let(y[i] / D[i] - sum((L[k][i] * x[k] for k in range(i + 1, n)), se.Integer(0)))
        columns.append(x)
    return [[columns[c][i] for c in range(len(B[0]))] for i in range(n)]


def ldl_substitution_map(program: Program, L: Matrix, D: list[se.Basic], columns: list[list[se.Basic]],
                         number: int = 0) -> ProgramMap:
    """The column map (:class:`~symkin.dynamics.program.ProgramMap`, function map ``number``) of x with
    L D L^T x = b for each of the ``columns`` b (n values each, of ``program``): one body, the substitutions of
    :func:`ldl_substitute` over the shared factors (L below its diagonal and 1/D, named in ``program``), so a
    backend with loops prints them once for all columns.  A column of numbers (e_c) or zeros costs the loop a full
    substitution; unrolled, its constant operations fold away."""
    n = len(L)
    below = [(i, k) for i in range(n) for k in range(i)]
    shared = ProgramMap.symbols(MAP_SHARED_PREFIX, len(below) + n)
    L_body: Matrix = [[se.Integer(0)] * n for _ in range(n)]
    for (i, k), symbol in zip(below, shared):
        L_body[i][k] = symbol
    parameters = ProgramMap.symbols(MAP_COLUMN_PREFIX, n)
    body = Program()
    x = ldl_substitute(body, L_body, [1 / s for s in shared[len(below):]], [[b] for b in parameters])
    return ProgramMap(shared, tuple([L[i][k] for i, k in below] + [program.let(1 / d) for d in D]), parameters, body,
                      tuple(row[0] for row in x), tuple(tuple(c) for c in columns),
                      ProgramMap.target_symbols(number, len(columns), n))


def transpose_solve(program: Program, J: Matrix, B: Matrix) -> Matrix:
    """X with J^T X = B for square nonsingular J (m x m) and B (m x r); see the module docstring."""
    m = len(J)
    if any(len(row) != m for row in J):
        raise ValueError("transpose_solve needs a square matrix")
    J = [[program.let(v) for v in row] for row in J]
    B = [[program.let(v) for v in row] for row in B]
    if m <= ADJUGATE_MAX_SIZE:
        return _adjugate_transpose_solve(program, J, B)
    return _gram_schmidt_transpose_solve(program, J, B)


def _det(A: Matrix) -> se.Basic:
    """Determinant by cofactor expansion along the first row (m <= 3)."""
    m = len(A)
    if m == 1:
        return A[0][0]
    return sum(((-1) ** c * A[0][c] * _det(_minor(A, 0, c)) for c in range(m)), se.Integer(0))


def _minor(A: Matrix, row: int, col: int) -> Matrix:
    return [[v for c, v in enumerate(r) if c != col] for k, r in enumerate(A) if k != row]


def _adjugate_transpose_solve(program: Program, J: Matrix, B: Matrix) -> Matrix:
    """J^-T B = cof(J) B / det(J), cof(J)_ij = (-1)^(i+j) det(minor_ij(J))."""
    m = len(J)
    cofactor = [[program.let((-1) ** (i + j) * _det(_minor(J, i, j))) if m > 1 else se.Integer(1)
                 for j in range(m)] for i in range(m)]
    det = program.let(sum((J[0][c] * cofactor[0][c] for c in range(m)), se.Integer(0)))
    inverse = program.let(1 / det)
    return [[program.let(sum((cofactor[i][k] * B[k][c] for k in range(m)), se.Integer(0)) * inverse)
             for c in range(len(B[0]))] for i in range(m)]


def _gram_schmidt_transpose_solve(program: Program, J: Matrix, B: Matrix) -> Matrix:
    """Augmented square-root-free modified Gram-Schmidt: J^T = U T, then T X = D^-1 U^T B by back substitution
    (T unit upper triangular, D = diag(|u_k|^2))."""
    m = len(J)
    a = [[J[j][i] for i in range(m)] for j in range(m)]  # a[k] = column k of J^T = row k of J
    b = [[B[i][c] for i in range(m)] for c in range(len(B[0]))]
    T: Matrix = [[se.Integer(0)] * m for _ in range(m)]
    y: Matrix = [[se.Integer(0)] * len(b) for _ in range(m)]
    for k in range(m):
        inverse = program.let(1 / program.let(dot(a[k], a[k])))
        for j in range(k + 1, m):
            T[k][j] = program.let(dot(a[k], a[j]) * inverse)
            a[j] = [program.let(a[j][i] - T[k][j] * a[k][i]) for i in range(m)]
        for c in range(len(b)):
            y[k][c] = program.let(dot(a[k], b[c]) * inverse)
            b[c] = [program.let(b[c][i] - y[k][c] * a[k][i]) for i in range(m)]
    X: Matrix = [[se.Integer(0)] * len(b) for _ in range(m)]
    for c in range(len(b)):
        for i in reversed(range(m)):
            X[i][c] = program.let(y[i][c] - sum((T[i][k] * X[k][c] for k in range(i + 1, m)), se.Integer(0)))
    return X
