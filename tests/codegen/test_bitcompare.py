"""Bit comparison: uint32 patterns, every bit counts — the sign of zero and NaN bits too."""
import numpy as np

from codegen import bitcompare, detmath


def test_bitcompare_every_bit_counts():
    x86_nan = np.uint32([0xFFC00000]).view(np.float32)
    arm_nan = np.uint32([0x7FC00000]).view(np.float32)
    assert not bitcompare.compare(x86_nan, arm_nan).ok          # no NaN class any more (issue 14)
    assert bitcompare.compare(detmath.canonf(x86_nan), detmath.canonf(arm_nan)).ok
    result = bitcompare.compare(np.float32([[0.0, 1.0], [np.nan, 2.0]]), np.float32([[-0.0, 1.0], [3.0, 2.0]]))
    assert result.n_mismatches == 2 and list(result.mismatched_rows) == [0, 1]
    assert result.first[0].expected_bits == 0 and result.first[0].actual_bits == 0x80000000
    assert "0x00000000" in result.report()[1] and "0x80000000" in result.report()[1]


def test_canonf_keeps_every_non_nan_and_makes_one_nan():
    bits = np.array([0, 0x80000000, 1, 0x7F7FFFFF, 0x7F800000, 0xFF800000, 0x7FC00000, 0xFFC00000, 0x7F800001,
                     0xFFFFFFFF, 0x7FC12345], dtype=np.uint32)
    out = detmath.canonf(bits.view(np.float32)).view(np.uint32)
    assert list(out[:6]) == list(bits[:6])
    assert set(out[6:].tolist()) == {0x7FC00000}
