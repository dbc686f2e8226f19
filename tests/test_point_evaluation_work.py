"""Point evaluations (the root finding and margins of the ICAD analysis) do per-point work only:
the ICAD kernel starts no parallel region for one row or a small grid, and a single model's
decomposition is done once per process. Both give the bits of the general path."""

import numpy as np
import scipy.linalg

from acdrive.analysis import _icad_frequency as icad_frequency
from acdrive.analysis import plant_for
from acdrive.analysis._freqresp import LTI
from acdrive.control import _ss_frequency as ss_frequency

K20 = LTI.paper_20()


def counting(monkeypatch, owner, name: str) -> list:
    """Replace ``owner.name`` by a wrapper that records each call; returns the record."""
    calls, real = [], getattr(owner, name)

    def wrapper(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(owner, name, wrapper)
    return calls


def test_one_parallel_region_per_grid_and_none_per_point(monkeypatch):
    """A point evaluation of one plant (one row) runs the serial kernel; a 100 x 2,000 grid
    runs the parallel kernel once."""
    regions = counting(monkeypatch, icad_frequency, "_icad_kernel")
    point = icad_frequency.PointEvaluator(plant_for("delorenzo-im", 200.0), K20, K20)
    for w in (10.0, 300.0, 3000.0):
        point.all(np.array([1j * w]))
    assert regions == []
    rng = np.random.default_rng(3)
    G = rng.normal(size=(100, 2000, 2, 2)) + 1j * rng.normal(size=(100, 2000, 2, 2))
    k = rng.normal(size=2000) + 1j * rng.normal(size=2000)
    icad_frequency.icad_quantities(G, k, k)
    assert len(regions) == 1


def test_the_serial_icad_kernel_has_its_own_cache_entry_and_the_same_bits():
    """Compiled from one loop with and without ``parallel``: each caches under its own name
    (numba's cache key ignores ``parallel``), and every output is bit for bit the same."""
    parallel, serial = icad_frequency._icad_kernel, icad_frequency._icad_kernel_serial
    assert parallel.targetoptions.get("parallel") is True
    assert serial.targetoptions.get("parallel") is None
    assert parallel._cache._cache_file._index_name != serial._cache._cache_file._index_name
    rng = np.random.default_rng(11)
    rows, K = 7, 301
    G = rng.normal(size=(rows, K, 2, 2)) + 1j * rng.normal(size=(rows, K, 2, 2))
    G[0, :5] *= 1e-160  # |z|^2 below the reciprocal's range: the complex division
    k1 = rng.normal(size=(1, K)) + 1j * rng.normal(size=(1, K))
    k2 = rng.normal(size=(rows, K)) + 1j * rng.normal(size=(rows, K))
    results = []
    for kernel in (parallel, serial):
        out = [np.empty((rows, K), complex)] + [np.empty((rows, K, 2), complex) for _ in range(3)]
        kernel(G, k1, k2, *out)
        results.append(out)
    for a, b in zip(*results, strict=True):
        assert a.tobytes() == b.tobytes()


def test_a_single_model_is_decomposed_once_for_many_points(monkeypatch):
    """Fifty one-point evaluations of one model decompose it once, with the bits of a batch
    evaluation at all points; a changed bit of A is a new model."""
    eig = counting(monkeypatch, np.linalg, "eig")
    plant = plant_for("delorenzo-im", 123.456789)  # a model no other test prepares
    A, B, C, D = (np.array(m, dtype=float) for m in (plant.A, plant.B, plant.C, plant.D))
    s = 1j * np.geomspace(1.0, 1e5, 50)
    one_by_one = np.stack([ss_frequency.evaluate_ss(A, B, C, D, [x])[0] for x in s])
    assert len(eig) == 1
    batch = ss_frequency.evaluate_ss(A[None], B[None], C[None], D[None], s)[0]
    assert one_by_one.tobytes() == batch.tobytes()

    A[0, 0] *= 1.5  # in place: the same array object, other bits
    changed = ss_frequency.evaluate_ss(A, B, C, D, s)
    assert changed.tobytes() == ss_frequency.evaluate_ss(A[None], B, C, D, s)[0].tobytes()
    assert not np.array_equal(changed, batch)


def test_a_defective_model_is_brought_to_hessenberg_form_once(monkeypatch):
    """The Hessenberg path (ill-conditioned eigenvectors) keeps its form too, with the bits of
    the batch evaluation and the resolvent's values."""
    forms = counting(monkeypatch, scipy.linalg, "hessenberg")
    A = np.array([[-2.0, 1.0, 0.0], [0.0, -2.0, 1.0], [0.0, 0.0, -2.0]])  # a Jordan block
    B, C, D = np.eye(3)[:, :2], np.eye(3)[:2], np.zeros((2, 2))
    s = np.array([1j, 3.0 + 2j, -1.0 + 40j])
    one_by_one = np.stack([ss_frequency.evaluate_ss(A, B, C, D, [x])[0] for x in s])
    assert len(forms) == 1
    batch = ss_frequency.evaluate_ss(A[None], B[None], C[None], D[None], s)[0]
    assert one_by_one.tobytes() == batch.tobytes()
    expected = C @ np.linalg.inv(s[:, None, None] * np.eye(3) - A) @ B
    np.testing.assert_allclose(one_by_one, expected, rtol=1e-12)
