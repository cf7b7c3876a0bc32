"""Issue 14 defect 3: the tanh law never outputs NaN or Inf, not even in its telemetry (x1, x2)
when a non-rotation R_c makes the law's intermediate values overflow."""
import numpy as np

from codegen.units.tanh.params import example_params
from host.sim.scenarios import configure_unit
from tools.runners import X86Runner


def test_no_output_is_ever_non_finite():
    unit = configure_unit("tanh", params=example_params())
    x86 = X86Runner(unit)
    checked = 0
    for seed in range(2):
        for batch in unit.gate_classes(200_000, seed).values():
            out, state = unit.golden(batch.state, batch.input)
            for name in ("torque", "x1", "x2", "varpi"):
                assert np.isfinite(out[name]).all(), name
            assert np.isfinite(state["varpi"]).all()
            c_out, _ = x86.records(batch)
            assert np.array_equal(out.view(np.uint8), c_out.view(np.uint8))
            checked += batch.input.shape[0]
    assert checked == 400_000
