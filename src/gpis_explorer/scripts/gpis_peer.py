"""The GPIS explorer update (paper 000 eq. 33-46) written independently in
numpy/scipy and with scikit-learn's GaussianProcessRegressor, for the timing
peers (bench_numpy_compare.py) and the agreement test (test/test_gpis_peer.py).

Kernel (000 eq. 33): k(x, x') = (c^2 + |x - x'|^2)^(-beta), beta 0.5, c 1,
noise sigma^2 1e-2. scikit-learn has no IMQ kernel; its RationalQuadratic is
  k_RQ(x, x') = (1 + |x - x'|^2 / (2 alpha l^2))^(-alpha)
and with alpha = beta, l^2 = c^2 / (2 beta) and a constant factor c^(-2 beta)
  c^(-2 beta) k_RQ = c^(-2 beta) (1 + |d|^2 / c^2)^(-beta) = (c^2 + |d|^2)^(-beta),
the IMQ kernel exactly (for c = 1, beta = 0.5: RationalQuadratic(l=1, alpha=0.5),
constant 1). GaussianProcessRegressor(alpha=sigma^2, optimizer=None) then
computes the same posterior (000 eq. 34-35): L = cholesky(K + sigma^2 I),
alpha_ = L^-T L^-1 y, mean = K* alpha_, var = k(x,x) - |L^-1 k*|^2.
"""
import contourpy
import numpy as np
from scipy.linalg import cho_factor, cho_solve, solve_triangular
from scipy.spatial.distance import cdist

BETA, C, NOISE = 0.5, 1.0, 1e-2
Q_CORNER, PEN, EXCL = -1.0, 0.2, 0.2  # 000 eq. 41 q, eq. 45 c, corner exclusion


def room_points(n, seed=42):
    """n points of a rotated 2 m room: 80 % wall contacts (1 cm noise, label 0),
    20 % interior (label -1); the same construction as bench/bench_gpis.cpp."""
    rng = np.random.default_rng(seed)
    X = np.zeros((n, 2))
    y = np.zeros(n)
    for i in range(n):
        if i % 5 == 4:
            X[i] = rng.uniform(-0.7, 0.7, 2)
            y[i] = -1.0
        else:
            t = rng.uniform(-1, 1)
            X[i] = [(t, -1.0), (t, 1.0), (-1.0, t), (1.0, t)][i % 4]
            X[i] += rng.normal(0, 0.01, 2)
    a = 0.3
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return X @ R.T, y


def kern(A, B):
    return (C ** 2 + cdist(A, B, "sqeuclidean")) ** (-BETA)  # 000 eq. 33


def sklearn_gpr():
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, RationalQuadratic
    k = RationalQuadratic(length_scale=C / np.sqrt(2 * BETA), alpha=BETA,
                          length_scale_bounds="fixed", alpha_bounds="fixed")
    if C ** (-2 * BETA) != 1.0:
        k = ConstantKernel(C ** (-2 * BETA), constant_value_bounds="fixed") * k
    return GaussianProcessRegressor(kernel=k, alpha=NOISE, optimizer=None, normalize_y=False)


def grid_nodes(cells, size=4.0):
    g = np.linspace(-size / 2, size / 2, cells)
    gx, gy = np.meshgrid(g, g)  # row-major, x fastest: the C++ GridSpec order
    return gx, gy, np.stack([gx.ravel(), gy.ravel()], 1)


def derivatives(P, X, alpha):
    """Gradient and Hessian of the mean (000 eq. 36-39) and curvature (eq. 40)."""
    D = P[:, None, :] - X[None, :, :]
    s = C ** 2 + np.sum(D * D, 2)
    s1 = s ** (-BETA - 1)
    grad = np.einsum("ij,ijk->ik", -2 * BETA * s1 * alpha, D)
    w = 4 * BETA * (BETA + 1) * s1 / s * alpha
    H = np.einsum("ij,ijk,ijl->ikl", w, D, D) + np.sum(-2 * BETA * s1 * alpha, 1)[:, None, None] * np.eye(2)
    gn = np.linalg.norm(grad, axis=1)
    kappa = (np.einsum("ni,nij,nj->n", grad, H, grad) - gn ** 2 * np.trace(H, axis1=1, axis2=2)) / gn ** 3
    return kappa


def corners_of(P, kappa, closed):
    """Runs of kappa < q and their centroids (000 eq. 41-42), the wrap merge on a
    closed contour (eq. 43)."""
    mask = kappa < Q_CORNER
    idx = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    cs = [P[a:b].mean(0) for a, b in zip(idx[::2], idx[1::2])]
    if closed and len(cs) >= 2 and mask[0] and mask[-1]:
        cs[0] = 0.5 * (cs[0] + cs[-1])
        cs.pop()
    return cs


def select_target(contours, variances, corners, lo, hi):
    """a~ = sigma^2 + P (000 eq. 44-46), corners within EXCL and points outside
    [lo, hi] excluded; the first maximum in contour order."""
    best, target = -np.inf, None
    for P, var in zip(contours, variances):
        pen = np.zeros(len(P))
        excl = np.any((P < lo) | (P > hi), 1)
        for ck in corners:
            d2 = np.sum((P - ck) ** 2, 1)
            pen = np.minimum(pen, -np.exp(-d2 / (2 * PEN ** 2)))
            excl |= d2 < EXCL ** 2
        acq = np.where(excl, -np.inf, var + pen)
        k = int(np.argmax(acq))
        if acq[k] > best:
            best, target = acq[k], P[k]
    return target


def contour_lines(gx, gy, mean, cells):
    lines = contourpy.contour_generator(gx, gy, mean.reshape(cells, cells)).lines(0.0)
    out = []
    for P in lines:
        closed = len(P) > 2 and np.array_equal(P[0], P[-1])
        out.append((P[:-1] if closed else P, closed))
    return out


def coarse_nodes(cells, vcells, size=4.0):
    return grid_nodes(vcells, size)[2] if vcells and vcells < cells else None


class NumpyGpis:
    """The update in numpy/scipy with an incremental Cholesky factor and an
    incrementally extended variance map, the same steps as GpisExplorer."""

    def __init__(self, cells, vcells, size=4.0, capacity=0):
        self.cells, self.size = cells, size
        self.gx, self.gy, self.G = grid_nodes(cells, size)
        self.Vn = coarse_nodes(cells, vcells, size)
        self.vc = vcells
        self.L = np.zeros((capacity, capacity))
        self.X = np.zeros((0, 2))
        self.y = np.zeros(0)
        self.V = None
        self.vrows = 0

    def fit(self, X, y):
        n = len(X)
        if self.L.shape[0] < n:
            self.L = np.zeros((n, n))
        self.L[:n, :n] = cho_factor(kern(X, X) + NOISE * np.eye(n), lower=True)[0]
        self.L[:n, :n][np.triu_indices(n, 1)] = 0.0
        self.X, self.y, self.vrows = X.copy(), y.copy(), 0
        self._alpha()

    def _alpha(self):
        n = len(self.X)
        L = self.L[:n, :n]
        self.alpha = solve_triangular(L, solve_triangular(L, self.y, lower=True), lower=True, trans="T")

    def add(self, Xn, yn):
        """New factor rows (O(n^2) each), then alpha."""
        for x, lab in zip(Xn, yn):
            n = len(self.X)
            l = solve_triangular(self.L[:n, :n], kern(self.X, x[None, :])[:, 0], lower=True) if n else np.zeros(0)
            self.L[n, :n] = l
            self.L[n, n] = np.sqrt(C ** (-2 * BETA) + NOISE - l @ l)
            self.X = np.vstack([self.X, x])
            self.y = np.append(self.y, lab)
        self._alpha()

    def pop(self, k):
        self.X, self.y = self.X[:-k], self.y[:-k]
        self.vrows = min(self.vrows, len(self.X))
        self._alpha()

    def variance_at(self, P):
        n = len(self.X)
        V = solve_triangular(self.L[:n, :n], kern(self.X, P), lower=True)
        return C ** (-2 * BETA) - np.sum(V * V, 0)

    def variance_map(self):
        n = len(self.X)
        if self.Vn is None:
            out = np.empty(len(self.G))
            for s in range(0, len(self.G), 512):
                out[s:s + 512] = self.variance_at(self.G[s:s + 512])
            return out
        if self.V is None or self.V.shape[0] < n:
            self.V = np.zeros((self.L.shape[0], len(self.Vn)))
            self.vrows = 0
        r0 = self.vrows
        if r0 == 0:
            self.V[:n] = solve_triangular(self.L[:n, :n], kern(self.X, self.Vn), lower=True)
        elif r0 < n:
            B = kern(self.X[r0:n], self.Vn) - self.L[r0:n, :r0] @ self.V[:r0]
            self.V[r0:n] = solve_triangular(self.L[r0:n, r0:n], B, lower=True)
        self.vrows = n
        cvar = C ** (-2 * BETA) - np.sum(self.V[:n] ** 2, 0)
        # bilinear onto the grid (the picture)
        t = np.linspace(0, self.vc - 1, self.cells)
        a = np.minimum(t.astype(int), self.vc - 2)
        u = t - a
        M = cvar.reshape(self.vc, self.vc)
        rows = (1 - u)[:, None] * M[a] + u[:, None] * M[a + 1]
        return ((1 - u)[None, :] * rows[:, a] + u[None, :] * rows[:, a + 1]).ravel()

    def update(self):
        mean = np.empty(len(self.G))
        for s in range(0, len(self.G), 512):
            mean[s:s + 512] = kern(self.G[s:s + 512], self.X) @ self.alpha  # 000 eq. 34
        var = self.variance_map()
        lines = contour_lines(self.gx, self.gy, mean, self.cells)
        corners = []
        for P, closed in lines:
            corners += corners_of(P, derivatives(P, self.X, self.alpha), closed)
        variances = [self.variance_at(P) for P, _ in lines]  # 000 eq. 35 at the contour points
        h = self.size / 2
        target = select_target([P for P, _ in lines], variances, corners, -h, h)
        return target, mean, var


def sklearn_update(X, y, cells, vcells, size=4.0):
    """The same update with scikit-learn (vcells: 0 every grid node, k a k x k
    map, None no variance map): fit (no incremental update in its API),
    predict the mean on the grid, predict with return_std on the contour points
    and the variance map."""
    gpr = sklearn_gpr().fit(X, y)
    gx, gy, G = grid_nodes(cells, size)
    mean = gpr.predict(G)
    std = None
    if vcells is not None:  # None: no variance map
        Vn = coarse_nodes(cells, vcells, size)
        _, std = gpr.predict(G if Vn is None else Vn, return_std=True)
    lines = contour_lines(gx, gy, mean, cells)
    corners, variances = [], []
    for P, closed in lines:
        corners += corners_of(P, derivatives(P, X, gpr.alpha_), closed)
        variances.append(gpr.predict(P, return_std=True)[1] ** 2)
    h = size / 2
    return select_target([P for P, _ in lines], variances, corners, -h, h), mean, None if std is None else std ** 2
