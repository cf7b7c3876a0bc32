"""Bit comparison: uint32 patterns, any NaN equals any NaN, the sign of zero counts."""
import numpy as np

from codegen import bitcompare


def test_bitcompare_nan_is_a_class_signed_zero_is_not():
    x86_nan = np.uint32([0xFFC00000]).view(np.float32)
    arm_nan = np.uint32([0x7FC00000]).view(np.float32)
    assert bitcompare.compare(x86_nan, arm_nan).ok
    result = bitcompare.compare(np.float32([[0.0, 1.0], [np.nan, 2.0]]), np.float32([[-0.0, 1.0], [3.0, 2.0]]))
    assert result.n_mismatches == 2 and list(result.mismatched_rows) == [0, 1]
    assert result.first[0].expected_bits == 0 and result.first[0].actual_bits == 0x80000000
    assert "0x00000000" in result.report()[1] and "0x80000000" in result.report()[1]
