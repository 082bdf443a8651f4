"""The published Table 1 (error = max_k |rodval - published| / max_k |published| per column)."""

import pytest

from rodval.analysis.reproduce import column_errors, compare_table1, run_paper_models


@pytest.fixture(scope="module", params=["printed", "published"])
def errors(request):
    table = compare_table1(run_paper_models(request.param))
    assert table["rodval"].notna().all()
    return request.param, column_errors(table).set_index(
        ["quantity", "formulation", "t"]
    ).sort_index()["error"]


def test_table1(errors):
    variant, err = errors
    if variant == "printed":
        # phi and phi' follow the equations as printed; alpha/beta are the erratum (20-40 % off)
        for f in "PR":
            assert err.loc["phi", f].max() < 2e-3
            assert err.loc["dphi", f].max() < 2e-2
        assert err.loc["alpha", "R"].min() > 0.1  # the published bending is not ours
    else:
        for q in ("phi", "dphi", "alpha", "beta"):
            assert err.loc[q, "R"].max() < 1e-2, q
        for q in ("phi", "dphi"):
            assert err.loc[q, "P"].max() < 1e-2, q
        for q in ("alpha", "beta"):
            early = err.loc[q, "P"]
            assert early[early.index <= 1.0].max() < 3e-2, q
