"""problems.warp_figure: the docs figure of the pre-warp draws what the ds-opt protocol measures."""
import pytest

import sosdyn as sd
from problems import warp_figure
from sosdyn.errors import SosdynError


@pytest.mark.slow      # experiment-sized: make test-slow
def test_warp_figure_on_doublebendedline(tmp_path):
    try:
        sd.load_lasa("DoubleBendedLine")
    except SosdynError as exc:
        pytest.skip(str(exc))
    res = warp_figure.figure("DoubleBendedLine", tmp_path)
    # the protocol's test DTWD of "CDSP plain" and "CDSP default" (reports/lasa_dsopt, random_state 0)
    assert res["scores"]["plain fit"] == pytest.approx(5140, rel=0.01)
    assert res["scores"]["default CDSP()"] == pytest.approx(1531, rel=0.01)
    assert min(res["warp_scores"], key=res["warp_scores"].get) != "none"      # a warp is kept
    assert (tmp_path / "warp_DoubleBendedLine.png").stat().st_size > 20_000
