"""Flash wait-state models of the STM32F4 at 168 MHz (RM0090 3.4-3.5: 5 wait states).

Both models see the same events: the 128-bit flash lines an executed block fetches, in order,
and each data read from flash (literal pools, `static const` tables). SRAM and CCM have no wait
states. The exact rules are stated in docs/cycle-model.md.
"""
from __future__ import annotations

from collections import OrderedDict

WAIT_STATES = 5
ART_I_LINES = 64
ART_D_LINES = 8


class ArtModel:
    """ART accelerator on: instruction cache 64 x 128 bit and data cache 8 x 128 bit,
    fully associative, least recently used replacement; every line miss costs 5 cycles."""

    name = "art"

    def __init__(self):
        self.icache: OrderedDict[int, None] = OrderedDict()
        self.dcache: OrderedDict[int, None] = OrderedDict()

    @staticmethod
    def _touch(cache: OrderedDict, line: int, capacity: int) -> int:
        if line in cache:
            cache.move_to_end(line)
            return 0
        cache[line] = None
        if len(cache) > capacity:
            cache.popitem(last=False)
        return WAIT_STATES

    def fetch(self, lines: tuple) -> int:
        extra = 0
        for ln in lines:
            extra += self._touch(self.icache, ln, ART_I_LINES)
        return extra

    def data(self, line: int) -> int:
        dcache = self.dcache
        if line in dcache:  # the common case, inlined: sequential weight reads
            dcache.move_to_end(line)
            return 0
        return self._touch(dcache, line, ART_D_LINES)


class PessimisticModel:
    """ART off (no caches, no prefetch): an instruction fetch pays 5 cycles whenever it needs a
    different 128-bit line than the previous fetch (only the flash read buffer is reused); every
    data read from flash pays 5 cycles."""

    name = "pessimistic"

    def __init__(self):
        self.line = -1

    def fetch(self, lines: tuple) -> int:
        extra = 0
        for ln in lines:
            if ln != self.line:
                extra += WAIT_STATES
                self.line = ln
        return extra

    def data(self, line: int) -> int:
        return WAIT_STATES
