"""Symbol names flight code must never reference: libm (SPEC section 5) or a vendor HAL."""
from __future__ import annotations

import re

LIBM = re.compile(r"^(__ieee754_\w+|__kernel_\w+|(a?sin|a?cos|a?tan|atan2|sinh|cosh|tanh|exp|exp2|"
                  r"expm1|log|log2|log10|log1p|pow|sqrt|cbrt|hypot|fmod|floor|ceil|round|"
                  r"trunc|frexp|ldexp|modf|erf|erfc|lgamma|tgamma)[fl]?)$")
HAL = re.compile(r"^(HAL_|LL_|SystemInit$|SystemCoreClock)")
ALLOCATION = re.compile(r"^(malloc|calloc|realloc|free)$")
