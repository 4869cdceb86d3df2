"""The decoupled parts of a state matrix (controllers.frequency.decoupled_parts): the weakly
connected components of its sparsity graph, numbered as scipy's graph search numbers them, on
both of its routes (dense closure for small graphs, scipy's search for large ones)."""
import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.csgraph

from controllers.frequency import decoupled_parts


def _scipy(pattern):
    return scipy.sparse.csgraph.connected_components(
        scipy.sparse.csr_matrix(pattern), directed=True, connection="weak")


@pytest.mark.parametrize("n_max", [40, 300])
def test_same_parts_and_numbering_as_scipy(n_max):
    # random directed patterns, sparse to dense, nodes shuffled (parts interleaved), with
    # chains (long paths: the closure needs several squarings) and isolated nodes
    rng = np.random.default_rng(n_max)
    for _ in range(60 if n_max < 100 else 8):
        n = int(rng.integers(1, n_max))
        pattern = rng.random((n, n)) < rng.uniform(0.0, 4.0 / max(n, 1))
        if n > 3 and rng.random() < 0.5:
            k = int(rng.integers(2, n))
            pattern[np.arange(k - 1), np.arange(1, k)] = True      # a chain of k nodes
        perm = rng.permutation(n)
        pattern = pattern[np.ix_(perm, perm)]
        n_parts, labels = decoupled_parts(pattern)
        n_ref, labels_ref = _scipy(pattern)
        assert n_parts == n_ref
        np.testing.assert_array_equal(labels, labels_ref)


def test_modal_matrix_and_limits():
    # a modal realisation: one part per 2 x 2 block, in the order of the blocks
    A = np.kron(np.eye(5), np.array([[0.0, 1.0], [-4.0, -0.1]]))
    n_parts, labels = decoupled_parts(A != 0.0)
    assert n_parts == 5
    np.testing.assert_array_equal(labels, np.repeat(np.arange(5), 2))
    # one coupling joins two blocks (either direction: weak connection)
    A[1, 6] = 1e-300
    n_parts, labels = decoupled_parts(A != 0.0)
    assert n_parts == 4 and labels[6] == labels[0] == 0 and labels[2] == 1
    # one node, no edges
    n_parts, labels = decoupled_parts(np.zeros((1, 1), dtype=bool))
    assert n_parts == 1 and labels.tolist() == [0]
