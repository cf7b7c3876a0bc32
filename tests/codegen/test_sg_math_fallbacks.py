"""sg_math's portable C99 fallbacks for GCC's builtins (issue 25, defect 19), forced with
-DSG_NO_BUILTINS: fabs by the sign bit and the integer sqrt give __builtin_fabsf's and
__builtin_sqrtf's bits (sqrtss here; VSQRT in test_detmath's ARM comparison) for every special
class, every subnormal, every significand of both exponent parities ([1, 4): all that a correctly
rounded sqrt's rounding depends on), each exponent's ends and 8 million random patterns."""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from codegen import detmath
from firmware.flags import COMMON, PORTABLE

CSRC = Path(detmath.__file__).resolve().parent / "csrc"

COMPARE_C = r"""
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "sg_math.h"

#if SG_HAVE_BUILTINS || !defined(SG_NO_BUILTINS)
#error "built without -DSG_NO_BUILTINS: this would compare the builtins with themselves"
#endif

static uint32_t bits(float f) { uint32_t u; memcpy(&u, &f, sizeof u); return u; }
static float from(uint32_t u) { float f; memcpy(&f, &u, sizeof f); return f; }

static unsigned long checked, bad;

/* The reference: the compiler's builtins, one instruction each under -fno-math-errno. */
static void check(uint32_t u)
{
    const float x = from(u);
    const uint32_t want_sqrt = bits(__builtin_sqrtf(x));
    const uint32_t want_fabs = bits(__builtin_fabsf(x));
    const uint32_t got_c99 = bits(sg_sqrtf_c99(x));
    const uint32_t got_api = bits(sg_sqrtf(x));
    const uint32_t got_fabs = bits(SG_FABSF(x));
    checked++;
    if (got_c99 != want_sqrt || got_api != want_sqrt || got_fabs != want_fabs) {
        if (bad < 5) {
            printf("mismatch x=%08lx sqrt %08lx %08lx want %08lx fabs %08lx want %08lx\n", (unsigned long)u,
                   (unsigned long)got_c99, (unsigned long)got_api, (unsigned long)want_sqrt,
                   (unsigned long)got_fabs, (unsigned long)want_fabs);
        }
        bad++;
    }
}

int main(void)
{
    static const uint32_t special[] = {
        0x00000000u, 0x80000000u, 0x7f800000u, 0xff800000u,              /* +-0, +-Inf */
        0x7fc00000u, 0xffc00000u, 0x7fffffffu, 0xffffffffu,              /* quiet NaNs */
        0x7f800001u, 0xff800001u, 0x7fbfffffu, 0xffbfffffu,              /* signalling NaNs */
        0x00000001u, 0x80000001u, 0x007fffffu, 0x807fffffu,              /* subnormal ends */
        0x00800000u, 0x80800000u, 0x7f7fffffu, 0xff7fffffu,              /* normal ends */
        0x3f800000u, 0xbf800000u, 0x40800000u, 0x3f7fffffu, 0x407fffffu  /* 1, -1, 4, below 1 and 4 */
    };
    uint32_t i;
    uint32_t s = 0x9e3779b9u;
    for (i = 0u; i < sizeof special / sizeof special[0]; i++) {
        check(special[i]);
    }
    for (i = 0u; i < 0x00800000u; i++) {          /* every subnormal (and zero), both signs */
        check(i);
        check(i | 0x80000000u);
    }
    for (i = 0x3f800000u; i < 0x40800000u; i++) { /* every significand, even and odd exponent */
        check(i);
    }
    for (i = 0u; i < 512u; i++) {                 /* each exponent and sign: both ends, a middle */
        check(i << 23);
        check((i << 23) | 0x007fffffu);
        check((i << 23) | 0x00400001u);
    }
    for (i = 0u; i < 8000000u; i++) {             /* random patterns (xorshift32) */
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        check(s);
    }
    printf("checked %lu mismatches %lu\n", checked, bad);
    return bad != 0u;
}
"""

# specials + 2 * 2^23 subnormals + 2^24 significands + 3 * 512 exponent ends + 8e6 random
EXPECTED_CHECKS = 25 + 2 * 2**23 + 2**24 + 3 * 512 + 8_000_000

FLAGS = {"gcc": COMMON, "clang": PORTABLE}


@pytest.mark.parametrize("cc", sorted(FLAGS))
def test_fallbacks_give_the_builtins_bits(tmp_path, cc):
    assert shutil.which(cc), f"{cc} not installed (tools/setup.sh installs it)"
    (tmp_path / "compare.c").write_text(COMPARE_C)
    exe = tmp_path / "compare"
    build = subprocess.run([cc, *FLAGS[cc], "-DSG_NO_BUILTINS", "-I", str(CSRC), str(tmp_path / "compare.c"),
                            str(CSRC / "sg_math.c"), "-o", str(exe)], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=600)
    m = re.search(r"checked (\d+) mismatches (\d+)", run.stdout)
    assert m is not None and run.returncode in (0, 1), run.stdout + run.stderr
    assert int(m.group(1)) == EXPECTED_CHECKS
    assert int(m.group(2)) == 0, run.stdout


def test_fallback_build_needs_no_libm_whatever_the_errno_flag(tmp_path):
    """Without builtins nothing calls libm, so math errno does not matter (the #error is for the
    builtin's libm call only)."""
    obj = tmp_path / "sg_math.o"
    flags = [f for f in COMMON if f != "-fno-math-errno"]
    subprocess.run(["gcc", *flags, "-fmath-errno", "-DSG_NO_BUILTINS", "-I", str(CSRC), "-c",
                    str(CSRC / "sg_math.c"), "-o", str(obj)], check=True, capture_output=True)
    nm = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    assert [ln.split()[-1] for ln in nm.splitlines() if ln.split()[0] == "U"] == []
