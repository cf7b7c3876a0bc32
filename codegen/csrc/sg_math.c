/*
 * sg_math.c - deterministic float32 math (see sg_math.h and docs/math.md).
 *
 * Rules that keep x86 SSE, ARM FPv4-SP and codegen/detmath.py bit-identical:
 *  - only +, -, *, /, sqrt on float, each rounded once (-ffp-contract=off: no FMA);
 *  - float -> integer only through the 1.5*2^23 magic add (k = (x + M) - M, and the low
 *    bits of x + M are k) or through the bit pattern, never through a C cast whose rounding
 *    or overflow could differ; integer -> float only for small integers (exact);
 *  - bit reinterpretation through a union (C99 type punning), mirrored by numpy .view();
 *  - coefficients are float32 values written as exact hex floats (tools/fit_minimax.py).
 */
#include <stdint.h>

#include "sg_math.h"

static uint32_t sg_as_u32(float f)
{
    sg_bits_t b;
    b.f = f;
    return b.u;
}

static float sg_as_f32(uint32_t u)
{
    sg_bits_t b;
    b.u = u;
    return b.f;
}

/* k + M has k in its low mantissa bits while |k| < 2^22 (round to nearest, ties to even). */
#define SG_MAGIC 0x1.8p+23f

/* ------------------------------------------------------------------ tanh */

/*
 * (SG_TANH_M, SG_TANH_FIRST, SG_TANH_N, sg_tanh_index, sg_tanh_poly: sg_math.h, shared with
 * sg_inline_tanhf.)
 * |x| in [2^-12, 9) is cut into 121 intervals, 8 per binade, indexed by the exponent and the
 * top 3 mantissa bits of x (one shift pair, one unsigned compare that also sends tiny, huge,
 * Inf and NaN arguments out of line). On each, tanh(c + t) = c0 + t (c1 + t (c2 + t (c3 +
 * t c4))), t = |x| - c (exact), c the interval's midpoint: a minimax fit for relative error
 * (tools/fit_minimax.py --tanh-table). No division: ~20 Cortex-M4 cycles inlined in the
 * network loop (sg_inline_tanhf), ~31 as a call.
 */

const float sg_tanh_tab[SG_TANH_N][SG_TANH_COLS] SG_TABLE(".sg_tables.sg_tanh_tab") = {
    /* BEGIN sg_tanh_tab: c, c0, c1, c2, c3, c4 */
    {0x1.1p-12f, 0x1.1p-12f, 0x1.fffffep-1f, -0x1.100012p-12f, -0x1.554f5cp-2f, 0x1.807d22p+0f},
    {0x1.3p-12f, 0x1.3p-12f, 0x1.fffffep-1f, -0x1.2ffff4p-12f, -0x1.554af4p-2f, 0x1.91be34p-2f},
    {0x1.5p-12f, 0x1.5p-12f, 0x1.fffffcp-1f, -0x1.500014p-12f, -0x1.55561cp-2f, 0x1.2d0c4ap+1f},
    {0x1.7p-12f, 0x1.7p-12f, 0x1.fffffcp-1f, -0x1.6ffff8p-12f, -0x1.5557f4p-2f, 0x1.b3a064p-2f},
    {0x1.9p-12f, 0x1.8ffffep-12f, 0x1.fffffcp-1f, -0x1.8fffd6p-12f, -0x1.5558ecp-2f, -0x1.0e4514p+1f},
    {0x1.bp-12f, 0x1.affffep-12f, 0x1.fffffap-1f, -0x1.b00024p-12f, -0x1.554fdp-2f, 0x1.0aacf2p+1f},
    {0x1.dp-12f, 0x1.cffffep-12f, 0x1.fffffap-1f, -0x1.cffffep-12f, -0x1.5557dep-2f, 0x1.88a8f8p+0f},
    {0x1.fp-12f, 0x1.effffep-12f, 0x1.fffff8p-1f, -0x1.effffcp-12f, -0x1.55598ap-2f, 0x1.3519cp-4f},
    {0x1.1p-11f, 0x1.0ffffep-11f, 0x1.fffff6p-1f, -0x1.0ffffep-11f, -0x1.555554p-2f, 0x1.b27e48p-4f},
    {0x1.3p-11f, 0x1.2ffffep-11f, 0x1.fffff4p-1f, -0x1.2ffffp-11f, -0x1.555534p-2f, -0x1.1f256cp-2f},
    {0x1.5p-11f, 0x1.4ffffcp-11f, 0x1.fffff2p-1f, -0x1.4ffff6p-11f, -0x1.5555d8p-2f, -0x1.a7ecbep-6f},
    {0x1.7p-11f, 0x1.6ffffcp-11f, 0x1.fffffp-1f, -0x1.6ffffp-11f, -0x1.5555p-2f, 0x1.a770fap-4f},
    {0x1.9p-11f, 0x1.8ffffap-11f, 0x1.ffffecp-1f, -0x1.8fffe6p-11f, -0x1.5555ccp-2f, -0x1.30852p-3f},
    {0x1.bp-11f, 0x1.affffap-11f, 0x1.ffffeap-1f, -0x1.afffecp-11f, -0x1.55539ap-2f, 0x1.53638cp-4f},
    {0x1.dp-11f, 0x1.cffff8p-11f, 0x1.ffffe6p-1f, -0x1.cfffd4p-11f, -0x1.55562ap-2f, -0x1.a27a2ap-3f},
    {0x1.fp-11f, 0x1.effff6p-11f, 0x1.ffffe2p-1f, -0x1.efffd4p-11f, -0x1.555478p-2f, -0x1.bb751ap-4f},
    {0x1.1p-10f, 0x1.0ffffap-10f, 0x1.ffffdcp-1f, -0x1.93b02p-5f, -0x1.45fbeep+2f, 0x1.8643aep+23f},
    {0x1.3p-10f, 0x1.2ffff8p-10f, 0x1.ffffd4p-1f, -0x1.d352dcp-4f, -0x1.5d2ebep+4f, 0x1.c829dep+24f},
    {0x1.5p-10f, 0x1.4ffff4p-10f, 0x1.ffffc8p-1f, -0x1.4fffdp-10f, -0x1.55551ep-2f, 0x1.176214p-7f},
    {0x1.7p-10f, 0x1.6ffffp-10f, 0x1.ffffbep-1f, 0x1.25eb58p-6f, -0x1.a01442p+0f, -0x1.3b2a84p+22f},
    {0x1.9p-10f, 0x1.8fffecp-10f, 0x1.ffffb2p-1f, -0x1.8fffaep-10f, -0x1.5553f8p-2f, -0x1.824b5cp-6f},
    {0x1.bp-10f, 0x1.afffe6p-10f, 0x1.ffffa4p-1f, 0x1.63d5b8p-5f, 0x1.423d6cp+4f, -0x1.6871e2p+23f},
    {0x1.dp-10f, 0x1.cfffep-10f, 0x1.ffff96p-1f, 0x1.c5e076p-6f, 0x1.16c852p+4f, -0x1.d5778ap+22f},
    {0x1.fp-10f, 0x1.efffdap-10f, 0x1.ffff88p-1f, -0x1.953e1p-4f, -0x1.c7b07ep+0f, 0x1.8b5338p+24f},
    {0x1.1p-9f, 0x1.0fffe6p-9f, 0x1.ffff6ep-1f, 0x1.71da2ap-6f, 0x1.0cd7c8p+3f, -0x1.83ecc2p+20f},
    {0x1.3p-9f, 0x1.2fffdcp-9f, 0x1.ffff4cp-1f, 0x1.dfeaa8p-7f, -0x1.a3d82ap+0f, -0x1.148dbp+20f},
    {0x1.5p-9f, 0x1.4fffdp-9f, 0x1.ffff24p-1f, -0x1.125afp-6f, -0x1.d37518p+1f, 0x1.c40f98p+19f},
    {0x1.7p-9f, 0x1.6fffcp-9f, 0x1.fffef6p-1f, 0x1.21db58p-5f, 0x1.1cb9b8p+3f, -0x1.30885ap+21f},
    {0x1.9p-9f, 0x1.8fffaep-9f, 0x1.fffec6p-1f, 0x1.1b1da6p-5f, 0x1.12d5e8p+3f, -0x1.2c471cp+21f},
    {0x1.bp-9f, 0x1.afff9ap-9f, 0x1.fffe94p-1f, -0x1.909978p-6f, -0x1.86e35ap+0f, 0x1.319bc4p+20f},
    {0x1.dp-9f, 0x1.cfff8p-9f, 0x1.fffe5ap-1f, 0x1.ca04dcp-5f, 0x1.37a916p+3f, -0x1.dd4a06p+21f},
    {0x1.fp-9f, 0x1.efff64p-9f, 0x1.fffe1ep-1f, 0x1.846b6ap-5f, 0x1.1dc642p+3f, -0x1.9afd8ep+21f},
    {0x1.1p-8f, 0x1.0fff9ap-8f, 0x1.fffdbep-1f, -0x1.e83bccp-7f, -0x1.0568fcp-1f, 0x1.5c04aep+17f},
    {0x1.3p-8f, 0x1.2fff72p-8f, 0x1.fffd3p-1f, -0x1.03512ap-5f, -0x1.db6092p+1f, 0x1.ad950cp+18f},
    {0x1.5p-8f, 0x1.4fff4p-8f, 0x1.fffc8ep-1f, -0x1.4ffcfcp-8f, -0x1.554c12p-2f, 0x1.203faap-8f},
    {0x1.7p-8f, 0x1.6fff02p-8f, 0x1.fffbdep-1f, 0x1.552784p-7f, -0x1.32159cp-2f, -0x1.04eabep+18f},
    {0x1.9p-8f, 0x1.8ffebap-8f, 0x1.fffb1ep-1f, 0x1.1da7aep-7f, -0x1.34ccd6p-2f, -0x1.e2bdb2p+17f},
    {0x1.bp-8f, 0x1.affe66p-8f, 0x1.fffa4ep-1f, -0x1.0fcd4ap-7f, -0x1.38fc5ap-2f, 0x1.bc242ap+14f},
    {0x1.dp-8f, 0x1.cffe04p-8f, 0x1.fff96ep-1f, -0x1.46bcc8p-7f, -0x1.2fac2ep-2f, 0x1.7905a4p+15f},
    {0x1.fp-8f, 0x1.effd94p-8f, 0x1.fff87ep-1f, -0x1.ba065cp-6f, -0x1.274f86p-2f, 0x1.3c459ap+18f},
    {0x1.1p-7f, 0x1.0ffe66p-7f, 0x1.fff6f8p-1f, 0x1.80d4fp-11f, -0x1.ef3b4ep-3f, -0x1.248206p+15f},
    {0x1.3p-7f, 0x1.2ffdc4p-7f, 0x1.fff4b8p-1f, -0x1.599bf2p-9f, -0x1.0e745ep-2f, -0x1.ae89e2p+14f},
    {0x1.5p-7f, 0x1.4ffcfcp-7f, 0x1.fff238p-1f, -0x1.8647fep-8f, -0x1.0f992ep-2f, -0x1.16a17cp+14f},
    {0x1.7p-7f, 0x1.6ffc0ap-7f, 0x1.ffef78p-1f, -0x1.2d44a2p-7f, -0x1.9cd8cap-3f, -0x1.03510ep+13f},
    {0x1.9p-7f, 0x1.8ffaeap-7f, 0x1.ffec78p-1f, -0x1.92268p-7f, -0x1.eecf1cp-3f, 0x1.e1d92cp+7f},
    {0x1.bp-7f, 0x1.aff998p-7f, 0x1.ffe938p-1f, -0x1.f4e7bep-7f, -0x1.a429f6p-3f, 0x1.11d08cp+13f},
    {0x1.dp-7f, 0x1.cff81p-7f, 0x1.ffe5bap-1f, -0x1.26a1e2p-6f, -0x1.55887ep-1f, 0x1.e63bb6p+13f},
    {0x1.fp-7f, 0x1.eff64ep-7f, 0x1.ffe1fap-1f, -0x1.50a24ap-6f, -0x1.3f70b2p-1f, 0x1.5afdd2p+14f},
    {0x1.1p-6f, 0x1.0ff99ap-6f, 0x1.ffdbe2p-1f, -0x1.0fe66ap-6f, -0x1.54f4fep-2f, 0x1.6a38c4p-7f},
    {0x1.3p-6f, 0x1.2ff712p-6f, 0x1.ffd2e2p-1f, -0x1.2fdc4ap-6f, -0x1.54dd04p-2f, 0x1.94163p-7f},
    {0x1.5p-6f, 0x1.4ff3f2p-6f, 0x1.ffc8e4p-1f, -0x1.8bedb6p-6f, -0x1.599a66p-2f, 0x1.dd885ep+11f},
    {0x1.7p-6f, 0x1.6ff02ap-6f, 0x1.ffbde6p-1f, -0x1.d9e336p-6f, -0x1.64e284p-2f, 0x1.a5b584p+12f},
    {0x1.9p-6f, 0x1.8feba8p-6f, 0x1.ffb1e8p-1f, -0x1.1db958p-6f, -0x1.55a58cp-2f, -0x1.c52dd8p+12f},
    {0x1.bp-6f, 0x1.afe66p-6f, 0x1.ffa4eap-1f, -0x1.6a4d28p-6f, -0x1.355cbcp-2f, -0x1.e8d0d4p+11f},
    {0x1.dp-6f, 0x1.cfe04p-6f, 0x1.ff96eep-1f, -0x1.59739p-6f, -0x1.43228p-2f, -0x1.d563fcp+12f},
    {0x1.fp-6f, 0x1.efd93ap-6f, 0x1.ff87f4p-1f, -0x1.231102p-5f, -0x1.cd2d3p-2f, 0x1.5407e6p+12f},
    {0x1.1p-5f, 0x1.0fe66cp-5f, 0x1.ff6f9ap-1f, -0x1.08dfdep-5f, -0x1.3b9cb6p-2f, -0x1.9bbe2cp+7f},
    {0x1.3p-5f, 0x1.2fdc4cp-5f, 0x1.ff4baap-1f, -0x1.38cffap-5f, -0x1.4f76bp-2f, 0x1.2a2e9ep+8f},
    {0x1.5p-5f, 0x1.4fcfccp-5f, 0x1.ff23bep-1f, -0x1.45ea04p-5f, -0x1.38b4b8p-2f, -0x1.20477p+8f},
    {0x1.7p-5f, 0x1.6fc0aep-5f, 0x1.fef7dap-1f, -0x1.621044p-5f, -0x1.3a3622p-2f, -0x1.934e9ep+8f},
    {0x1.9p-5f, 0x1.8faeb2p-5f, 0x1.fec7fep-1f, -0x1.7eae9p-5f, -0x1.387d8ep-2f, -0x1.f57e44p+8f},
    {0x1.bp-5f, 0x1.af999ap-5f, 0x1.fe942ep-1f, -0x1.c535ccp-5f, -0x1.5dcf7cp-2f, 0x1.574522p+9f},
    {0x1.dp-5f, 0x1.cf8124p-5f, 0x1.fe5c66p-1f, -0x1.ed22bep-5f, -0x1.531b4p-2f, 0x1.ef04a4p+9f},
    {0x1.fp-5f, 0x1.ef651p-5f, 0x1.fe20acp-1f, -0x1.d39586p-5f, -0x1.503faep-2f, -0x1.9d9c64p+9f},
    {0x1.1p-4f, 0x1.0f99d4p-4f, 0x1.fdbfb2p-1f, -0x1.12872ap-4f, -0x1.50c2b6p-2f, 0x1.04994ep+6f},
    {0x1.3p-4f, 0x1.2f716cp-4f, 0x1.fd30a6p-1f, -0x1.31694ep-4f, -0x1.512074p-2f, 0x1.7405ecp+5f},
    {0x1.5p-4f, 0x1.4f3f94p-4f, 0x1.fc91fp-1f, -0x1.493374p-4f, -0x1.49a7e8p-2f, -0x1.c4dc88p+5f},
    {0x1.7p-4f, 0x1.6f0356p-4f, 0x1.fbe3aap-1f, -0x1.6c11p-4f, -0x1.4a6f64p-2f, 0x1.df7bdap-5f},
    {0x1.9p-4f, 0x1.8ebbb8p-4f, 0x1.fb25e8p-1f, -0x1.90264p-4f, -0x1.49c90ap-2f, 0x1.4a7f5ap+6f},
    {0x1.bp-4f, 0x1.ae67cp-4f, 0x1.fa58bep-1f, -0x1.a1dfdp-4f, -0x1.44c0fcp-2f, -0x1.ee8074p+6f},
    {0x1.dp-4f, 0x1.ce067ep-4f, 0x1.f97c4ap-1f, -0x1.cb8bf8p-4f, -0x1.49526p-2f, 0x1.aa7184p+5f},
    {0x1.fp-4f, 0x1.ed96fap-4f, 0x1.f890a2p-1f, -0x1.ed75ccp-4f, -0x1.40d682p-2f, 0x1.c062eap+6f},
    {0x1.1p-3f, 0x1.0e6974p-3f, 0x1.f712ecp-1f, -0x1.0a4d7ap-3f, -0x1.3e58d6p-2f, 0x1.210e7ap+2f},
    {0x1.3p-3f, 0x1.2dc968p-3f, 0x1.f4e1e4p-1f, -0x1.257d84p-3f, -0x1.34c204p-2f, -0x1.ae4946p+3f},
    {0x1.5p-3f, 0x1.4d0478p-3f, 0x1.f2765ap-1f, -0x1.43ce8p-3f, -0x1.30b434p-2f, -0x1.825872p+1f},
    {0x1.7p-3f, 0x1.6c1702p-3f, 0x1.efd174p-1f, -0x1.603b74p-3f, -0x1.2ae9d6p-2f, -0x1.10e838p+1f},
    {0x1.9p-3f, 0x1.8afd7cp-3f, 0x1.ecf476p-1f, -0x1.7d19cp-3f, -0x1.23de5cp-2f, 0x1.a0541cp+2f},
    {0x1.bp-3f, 0x1.a9b46ep-3f, 0x1.e9e0bcp-1f, -0x1.98eb1p-3f, -0x1.1ca2acp-2f, 0x1.9ccfbep+3f},
    {0x1.dp-3f, 0x1.c83876p-3f, 0x1.e697b6p-1f, -0x1.b0077p-3f, -0x1.13d4c4p-2f, -0x1.86cdaep+3f},
    {0x1.fp-3f, 0x1.e6865p-3f, 0x1.e31aeep-1f, -0x1.cb45d6p-3f, -0x1.0b7e48p-2f, 0x1.c545b6p+0f},
    {0x1.1p-2f, 0x1.09c744p-2f, 0x1.dd823ap-1f, -0x1.eed1a8p-3f, -0x1.fb4fcp-3f, -0x1.afa94ap+0f},
    {0x1.3p-2f, 0x1.275f7ep-2f, 0x1.d56658p-1f, -0x1.0ebe52p-2f, -0x1.d5161cp-3f, -0x1.91ec92p-5f},
    {0x1.5p-2f, 0x1.447066p-2f, 0x1.cc9a6ap-1f, -0x1.245bep-2f, -0x1.ad3d98p-3f, 0x1.0d1c9cp+1f},
    {0x1.7p-2f, 0x1.60ef72p-2f, 0x1.c32d96p-1f, -0x1.375766p-2f, -0x1.836feep-3f, 0x1.62ad14p+0f},
    {0x1.9p-2f, 0x1.7cd312p-2f, 0x1.b92f98p-1f, -0x1.487536p-2f, -0x1.591a74p-3f, 0x1.5c7b9ep+0f},
    {0x1.bp-2f, 0x1.9812b4p-2f, 0x1.aeb08cp-1f, -0x1.576bbap-2f, -0x1.2c95fap-3f, 0x1.900f32p-1f},
    {0x1.dp-2f, 0x1.b2a6cap-2f, 0x1.a3c0c2p-1f, -0x1.648c62p-2f, -0x1.012cbap-3f, 0x1.fe5a74p-1f},
    {0x1.fp-2f, 0x1.cc88cap-2f, 0x1.987084p-1f, -0x1.6f997p-2f, -0x1.ac1268p-4f, 0x1.066c1cp+0f},
    {0x1.1p-1f, 0x1.f20212p-2f, 0x1.86e67ep-1f, -0x1.7c434p-2f, -0x1.2eca64p-4f, 0x1.a258fp-3f},
    {0x1.3p-1f, 0x1.10af48p-1f, 0x1.6ec588p-1f, -0x1.86b4c2p-2f, -0x1.24064p-5f, 0x1.69052cp-3f},
    {0x1.5p-1f, 0x1.26d77p-1f, 0x1.56363cp-1f, -0x1.8a33dep-2f, -0x1.40053ep-10f, 0x1.78ab58p-3f},
    {0x1.7p-1f, 0x1.3b75f8p-1f, 0x1.3da23cp-1f, -0x1.873adp-2f, 0x1.d57edcp-6f, -0x1.1cf2cap-4f},
    {0x1.9p-1f, 0x1.4e8d8ap-1f, 0x1.25653p-1f, -0x1.7f91b6p-2f, 0x1.b6fa9cp-5f, 0x1.d5e438p-3f},
    {0x1.bp-1f, 0x1.60260ap-1f, 0x1.0dcbbp-1f, -0x1.73354ep-2f, 0x1.2d591ap-4f, 0x1.3842bp-3f},
    {0x1.dp-1f, 0x1.704bb2p-1f, 0x1.ee264cp-2f, -0x1.638668p-2f, 0x1.6b9126p-4f, 0x1.ef1a1cp-4f},
    {0x1.fp-1f, 0x1.7f0e1ap-1f, 0x1.c2d4ccp-2f, -0x1.513c0ap-2f, 0x1.98242ap-4f, -0x1.14d4a8p-6f},
    {0x1.1p+0f, 0x1.92bfb4p-1f, 0x1.866162p-2f, -0x1.331c5ap-2f, 0x1.bd4dc6p-4f, 0x1.5987fap-6f},
    {0x1.3p+0f, 0x1.a8dbccp-1f, 0x1.3ee73p-2f, -0x1.08a338p-2f, 0x1.c4dd5p-4f, -0x1.aa24dap-9f},
    {0x1.5p+0f, 0x1.bad50ap-1f, 0x1.01fba8p-2f, -0x1.be3ae6p-3f, 0x1.abd448p-4f, -0x1.5de418p-6f},
    {0x1.7p+0f, 0x1.c950a4p-1f, 0x1.9e1e04p-3f, -0x1.71e31p-3f, 0x1.8091bp-4f, -0x1.82fa02p-6f},
    {0x1.9p+0f, 0x1.d4e6f4p-1f, 0x1.4a4584p-3f, -0x1.2e7248p-3f, 0x1.4dd61ep-4f, -0x1.c7ef04p-6f},
    {0x1.bp+0f, 0x1.de1eb6p-1f, 0x1.06129cp-3f, -0x1.e990d4p-4f, 0x1.1a666p-4f, -0x1.27f4bap-6f},
    {0x1.dp+0f, 0x1.e56b7p-1f, 0x1.9e3efep-4f, -0x1.88d5b6p-4f, 0x1.d4a7bcp-5f, -0x1.1f8b5cp-6f},
    {0x1.fp+0f, 0x1.eb2dfep-1f, 0x1.465a1ep-4f, -0x1.38de0cp-4f, 0x1.7f48ap-5f, -0x1.0badf8p-5f},
    {0x1.1p+1f, 0x1.f1994ep-1f, 0x1.c65a6ep-5f, -0x1.b9939ap-5f, 0x1.1668fp-5f, -0x1.eb1f12p-7f},
    {0x1.3p+1f, 0x1.f73776p-1f, 0x1.16a7fcp-5f, -0x1.11d4d4p-5f, 0x1.6159ccp-6f, -0x1.517292p-7f},
    {0x1.5p+1f, 0x1.faa794p-1f, 0x1.5452p-6f, -0x1.50daa8p-6f, 0x1.b8ad14p-7f, -0x1.93f774p-8f},
    {0x1.7p+1f, 0x1.fcc04cp-1f, 0x1.9e87ccp-7f, -0x1.9b9652p-7f, 0x1.0fccf8p-7f, -0x1.2cf566p-8f},
    {0x1.9p+1f, 0x1.fe06ecp-1f, 0x1.f81bdp-8f, -0x1.f6ee04p-8f, 0x1.4d1286p-8f, -0x1.da9fcep-10f},
    {0x1.bp+1f, 0x1.fecd6cp-1f, 0x1.3238b4p-8f, -0x1.31cf7p-8f, 0x1.96856p-9f, -0x1.4f4a76p-10f},
    {0x1.dp+1f, 0x1.ff45f6p-1f, 0x1.73ceb2p-9f, -0x1.7209c6p-9f, 0x1.eeff3cp-10f, -0x1.873eccp-10f},
    {0x1.fp+1f, 0x1.ff8f22p-1f, 0x1.c347p-10f, -0x1.c36dbp-10f, 0x1.2ce52ep-10f, -0x1.dbd54p-12f},
    {0x1.1p+2f, 0x1.ffcaacp-1f, 0x1.aa7d66p-11f, -0x1.aa25d6p-11f, 0x1.1fe53ap-11f, -0x1.229d94p-12f},
    {0x1.3p+2f, 0x1.ffec62p-1f, 0x1.39e744p-12f, -0x1.3c592cp-12f, 0x1.a6fb1p-13f, -0x1.14293cp-14f},
    {0x1.5p+2f, 0x1.fff8c8p-1f, 0x1.cdf58ep-14f, -0x1.cd02b4p-14f, 0x1.37501p-14f, -0x1.4e31ccp-15f},
    {0x1.7p+2f, 0x1.fffd58p-1f, 0x1.53e6b4p-15f, -0x1.501a82p-15f, 0x1.ca3726p-16f, -0x1.4dfa46p-16f},
    {0x1.9p+2f, 0x1.ffff06p-1f, 0x1.f42d44p-17f, -0x1.fb8b66p-17f, 0x1.512878p-17f, -0x1.0417bap-19f},
    {0x1.bp+2f, 0x1.ffffa4p-1f, 0x1.70035p-18f, -0x1.7050fep-18f, 0x1.f00868p-19f, -0x1.e1f006p-20f},
    {0x1.dp+2f, 0x1.ffffdep-1f, 0x1.0ebf1cp-19f, -0x1.a54192p-20f, 0x1.6ddedep-20f, -0x1.e73fcep-18f},
    {0x1.fp+2f, 0x1.fffff4p-1f, 0x1.8e607p-21f, -0x1.ae3c1p-20f, 0x1.0dce06p-21f, 0x1.692c9ap-17f},
    {0x1.1p+3f, 0x1.fffffep-1f, 0x1.62f69ep-23f, -0x1.5f1a5ap-21f, 0x1.f5a386p-24f, 0x1.bf5a74p-20f},
    /* END sg_tanh_tab */
};

/* d = (ux << 1) - SG_TANH_D_FIRST: magnitude bits of x (2 per ulp) above those of 2^-12, the
 * start of interval 0; the interval is d >> SG_TANH_SHIFT, i.e. sg_tanh_index(ux), and
 * d >= SG_TANH_D_END outside [2^-12, 9) (SG_TANH_SHIFT, SG_TANH_D_*: sg_math.h). */

/* Outside [2^-12, 9): x itself for NaN (NaN in, NaN out) and for |x| < 2^-12 (also +-0,
 * subnormals: d wrapped around), else +-1 (|x| >= 9, +-Inf; tanh 9 is within 0.52 ulp of 1).
 * One unsigned compare: a network row with an infinite or NaN input comes here once per hidden
 * neuron. */
static float sg_tanh_outside(float x, uint32_t ux, uint32_t d)
{
    float r = x;
    if (d <= SG_TANH_D_INF) {
        r = sg_as_f32((ux & 0x80000000u) | 0x3f800000u); /* +-1 from the sign bit: no IT block */
    }
    return r;
}

/* tanh(x) = MATLAB tansig(x); odd: the sign is applied last from the sign bit. The interval
 * comes from d (same value as sg_tanh_index(ux)), which the out-of-range path reuses. */
float sg_tanhf(float x)
{
    uint32_t ux = sg_as_u32(x);
    uint32_t d = (ux << 1) - SG_TANH_D_FIRST;
    float r;
    if (SG_EXPECT(d >= SG_TANH_D_END, 0) != 0) {
        r = sg_tanh_outside(x, ux, d);
    } else {
        r = sg_tanh_poly(sg_tanh_tab[d >> SG_TANH_SHIFT], x, ux);
    }
    return r;
}

/* ------------------------------------------------------------------ exp */

#define SG_INV_LN2 0x1.715476p+0f
#define SG_LN2_HI 0x1.62e4p-1f        /* 15 significant bits: k * it is exact for |k| < 512 */
#define SG_LN2_LO 0x1.7f7d1cp-20f     /* ln2 - SG_LN2_HI */
#define SG_EXP_OVF 0x1.62e42ep+6f     /* 88.7228317: largest x with e^x <= FLT_MAX */
#define SG_EXP_UNF -0x1.9fe368p+6f    /* -103.972076: below, e^x < 2^-150 rounds to +0 */

static float sg_inf(void)
{
    return sg_as_f32(0x7f800000u);
}

static float sg_nan(void)
{
    return sg_as_f32(0x7fc00000u);
}

/* 2^(k + bias) from u = bits of (k + SG_MAGIC), valid while -126 <= k + bias <= 127. */
static float sg_pow2(uint32_t u, uint32_t bias)
{
    return sg_as_f32((u + bias + 127u) << 23);
}

/* e^r - 1 on |r| <= ln2/2: r (1 + r/2 + c2 r^2 + ... + c5 r^5). */
static float sg_expm1_kernel(float r)
{
    float p = 0x1.6c5a98p-10f;
    p = (p * r) + 0x1.12243ap-7f;
    p = (p * r) + 0x1.5555b6p-5f;
    p = (p * r) + 0x1.5554b6p-3f;
    p = (p * r) + 0.5f;
    p = (p * r) + 1.0f;
    return p * r;
}

/* e^x for |x| > 87 (k = round(x/ln2) may leave [-126, 127]), NaN, +-Inf. */
static float sg_exp_outer(float x)
{
    if (!((x <= SG_EXP_OVF) && (x >= SG_EXP_UNF))) {
        if (x != x) {
            return x + x;
        }
        return (x > 0.0f) ? sg_inf() : 0.0f;
    }
    float t = (x * SG_INV_LN2) + SG_MAGIC;
    float kf = t - SG_MAGIC;
    float q = sg_expm1_kernel((x - (kf * SG_LN2_HI)) - (kf * SG_LN2_LO));
    uint32_t u = sg_as_u32(t);
    if ((kf >= -126.0f) && (kf <= 127.0f)) {
        float s = sg_pow2(u, 0u);
        return s + (s * q);
    }
    if (kf > 0.0f) {
        float s = sg_pow2(u, (uint32_t)-1);
        return (s + (s * q)) * 2.0f;
    }
    float s = sg_pow2(u, 64u);
    return (s + (s * q)) * 0x1p-64f;
}

/*
 * e^x = 2^k (1 + q), k = round(x/ln2), r = x - k ln2 (Cody-Waite, two parts) in
 * [-ln2/2, ln2/2], q = e^r - 1. The result is formed as s + s q with s = 2^k (one rounding).
 * |x| <= 87 keeps k in [-126, 126]; the rest (same arithmetic, two-step scaling for k outside
 * [-126, 127], overflow, underflow, NaN) is out of line.
 */
float sg_expf(float x)
{
    float r;
    if (SG_EXPECT(!(SG_FABSF(x) <= 87.0f), 0) != 0) {
        r = sg_exp_outer(x);
    } else {
        float t = (x * SG_INV_LN2) + SG_MAGIC;
        float kf = t - SG_MAGIC;
        float q = sg_expm1_kernel((x - (kf * SG_LN2_HI)) - (kf * SG_LN2_LO));
        float s = sg_pow2(sg_as_u32(t), 0u);
        r = s + (s * q);
    }
    return r;
}

/* ------------------------------------------------------------------ log */

/*
 * x = 2^k m, m in [sqrt(1/2), sqrt(2)), f = m - 1 (exact), s = f/(2+f), z = s^2:
 * ln(1+f) = f - f^2/2 + s (f^2/2 + R(z)), R(z) = 2 atanh(s)/s - 2 = z (c1 + c2 z + c3 z^2),
 * summed small terms first (fdlibm's arrangement); ln x = that + k ln2 (hi/lo).
 */
float sg_logf(float x)
{
    uint32_t ix = sg_as_u32(x);
    float kbias = 0.0f;
    if (SG_EXPECT((ix < 0x00800000u) || (ix >= 0x7f800000u), 0) != 0) {
        if ((ix << 1) == 0u) {
            return -sg_inf();
        }
        if ((x != x) || (ix == 0x7f800000u)) {
            return x + x;
        }
        if ((ix >> 31) != 0u) {
            return sg_nan();
        }
        ix = sg_as_u32(x * 0x1p23f);
        kbias = -23.0f;
    }
    ix += 0x3f800000u - 0x3f3504f3u;
    int32_t k = (int32_t)(ix >> 23) - 127;
    float kf = (float)k + kbias;
    float f = sg_as_f32((ix & 0x007fffffu) + 0x3f3504f3u) - 1.0f;
    float s = f / (2.0f + f);
    float z = s * s;
    float rz = 0x1.2f29fep-2f;
    rz = (rz * z) + 0x1.997aa8p-2f;
    rz = (rz * z) + 0x1.55555cp-1f;
    rz = rz * z;
    float hfsq = 0.5f * f * f;
    return ((((s * (hfsq + rz)) + (kf * SG_LN2_LO)) - hfsq) + f) + (kf * SG_LN2_HI);
}

/* ------------------------------------------------------------------ sin, cos */

#define SG_TWO_OVER_PI 0x1.45f306p-1f
/* pi/2 = P1 + P2 + P3 + P4 + O(2^-63); P1..P3 have 11 significant bits so j * Pi is exact
 * for |j| < 2^13, i.e. |x| <= 8192 (= SG_TRIG_MAX_ARG). */
#define SG_PIO2_1 0x1.92p+0f
#define SG_PIO2_2 0x1.fb4p-12f
#define SG_PIO2_3 0x1.444p-24f
#define SG_PIO2_4 0x1.68c234p-39f
#define SG_PIO4 0x1.921fb6p-1f

/* sin(hi + lo) on |hi| <= pi/4: hi + (hi z (s3 + s5 z + s7 z^2) + lo). */
static float sg_sin_kernel(float hi, float lo)
{
    float z = hi * hi;
    float p = -0x1.9952ecp-13f;
    p = (p * z) + 0x1.110776p-7f;
    p = (p * z) - 0x1.555546p-3f;
    return hi + ((hi * (z * p)) + lo);
}

/* cos(hi + lo) on |hi| <= pi/4: 1 - (z/2 - (z^2 (c4 + c6 z + c8 z^2) - hi lo)). */
static float sg_cos_kernel(float hi, float lo)
{
    float z = hi * hi;
    float p = 0x1.9b8a82p-16f;
    p = (p * z) - 0x1.6c123cp-10f;
    p = (p * z) + 0x1.555554p-5f;
    return 1.0f - ((0.5f * z) - ((z * (z * p)) - (hi * lo)));
}

/*
 * sin(x + shift * pi/2) (shift 0: sin, 1: cos). x = j pi/2 + (hi + lo), Cody-Waite in four
 * parts; lo keeps the rounding error of the last subtraction (Fast2Sum) and the P4 term, so
 * tiny |r| near multiples of pi/2 keep their relative accuracy. Quadrant n = j + shift mod 4
 * selects sin, cos, -sin, -cos. Beyond SG_TRIG_MAX_ARG the reduced argument is clamped to
 * [-pi/4, pi/4]: a finite, bounded, but meaningless result.
 */
static float sg_trig(float x, uint32_t shift)
{
    float t = (x * SG_TWO_OVER_PI) + SG_MAGIC;
    float jf = t - SG_MAGIC;
    float t2 = (x - (jf * SG_PIO2_1)) - (jf * SG_PIO2_2);
    float w = jf * SG_PIO2_3;
    float hi = t2 - w;
    float lo = ((t2 - hi) - w) - (jf * SG_PIO2_4);
    if (SG_EXPECT(!(SG_FABSF(x) <= SG_TRIG_MAX_ARG), 0) != 0) {
        hi = (hi > SG_PIO4) ? SG_PIO4 : ((hi < -SG_PIO4) ? -SG_PIO4 : hi);
        lo = 0.0f;
    }
    uint32_t n = sg_as_u32(t) + shift;
    float y = ((n & 1u) != 0u) ? sg_cos_kernel(hi, lo) : sg_sin_kernel(hi, lo);
    return ((n & 2u) != 0u) ? -y : y;
}

float sg_sinf(float x)
{
    /* sin x rounds to x below 2^-12; also keeps sin(-0) = -0 and passes NaN. */
    float r;
    if (!(SG_FABSF(x) >= 0x1p-12f)) {
        r = x;
    } else {
        r = sg_trig(x, 0u);
    }
    return r;
}

float sg_cosf(float x)
{
    return sg_trig(x, 1u);
}

/* ------------------------------------------------------------------ asin, atan2 */

#define SG_PIO2_HI 0x1.921fb6p+0f
#define SG_PIO2_LO -0x1.777a5cp-25f  /* pi/2 - SG_PIO2_HI */
#define SG_PI_HI 0x1.921fb6p+1f
#define SG_PI_LO -0x1.777a5cp-24f

/* asin(x) - x on |x| <= 1/2: x z (a3 + a5 z + ... + a11 z^4), z = x^2. */
static float sg_asin_tail(float x, float z)
{
    float p = 0x1.596d5cp-5f;
    p = (p * z) + 0x1.8c2d86p-6f;
    p = (p * z) + 0x1.747d06p-5f;
    p = (p * z) + 0x1.3301fcp-4f;
    p = (p * z) + 0x1.5555c8p-3f;
    return x * (z * p);
}

/*
 * |x| < 1/2: the odd polynomial. |x| >= 1/2: asin a = pi/2 - 2 asin(s), s = sqrt((1 - a)/2)
 * (1 - a and the halving are exact). pi/2 - 2s is exact for s >= 0.3125 (the difference is
 * below 1, a multiple of ulp(2s)); there it is formed first, else 2s absorbs the small terms.
 */
float sg_asinf(float x)
{
    float a = SG_FABSF(x);
    float r;
    if (SG_EXPECT(!(a <= 1.0f), 0) != 0) {
        r = (x == x) ? sg_nan() : (x + x);
    } else if (a < 0.5f) {
        if (a < 0x1p-12f) {
            r = x; /* asin x rounds to x; keeps -0 */
        } else {
            r = x + sg_asin_tail(x, x * x);
        }
    } else {
        float z = (1.0f - a) * 0.5f;
        float s = SG_SQRTF(z);
        float u = (2.0f * sg_asin_tail(s, z)) - SG_PIO2_LO;
        float y = (s >= 0.3125f) ? ((SG_PIO2_HI - (2.0f * s)) - u) : (SG_PIO2_HI - ((2.0f * s) + u));
        r = (x < 0.0f) ? -y : y;
    }
    return r;
}

/* atan(q) on 0 <= q <= 1: q + q z (b3 + b5 z + ... + b19 z^8), z = q^2. */
static float sg_atan_kernel(float q)
{
    float z = q * q;
    float p = -0x1.d32dacp-10f;
    p = (p * z) + 0x1.6410e4p-7f;
    p = (p * z) - 0x1.fd6fbcp-6f;
    p = (p * z) + 0x1.da24cap-5f;
    p = (p * z) - 0x1.580814p-4f;
    p = (p * z) + 0x1.c08c1ap-4f;
    p = (p * z) - 0x1.242084p-3f;
    p = (p * z) + 0x1.9991e4p-3f;
    p = (p * z) - 0x1.55553ep-2f;
    return q + (q * (z * p));
}

/* Annex F cases: a zero, an infinity or a NaN among the arguments (a = |y|, b = |x|). */
static float sg_atan2_special(float y, float x, float a, float b, uint32_t xneg)
{
    float inf = sg_inf();
    float t;
    if ((x != x) || (y != y)) {
        return x + y;
    }
    if (a == inf) {
        t = (b == inf) ? ((xneg != 0u) ? 0x1.2d97c8p+1f : 0x1.921fb6p-1f) : SG_PIO2_HI;
    } else if ((b == inf) || (a == 0.0f)) {
        t = (xneg != 0u) ? SG_PI_HI : 0.0f;
    } else {
        t = SG_PIO2_HI; /* b == 0, a finite non-zero */
    }
    return ((sg_as_u32(y) >> 31) != 0u) ? -t : t;
}

/*
 * q = min(a,b)/max(a,b) in [0, 1], t = atan q; t -> pi/2 - t if a > b, t -> pi - t if x < 0,
 * sign of y. pi/2 and pi as hi + lo with the lo part added to the small term first.
 */
float sg_atan2f(float y, float x)
{
    float a = SG_FABSF(y);
    float b = SG_FABSF(x);
    uint32_t xneg = sg_as_u32(x) >> 31;
    float inf = sg_inf();
    float r;
    if (SG_EXPECT(((a > 0.0f) && (a < inf) && (b > 0.0f) && (b < inf)), 1) == 0) {
        r = sg_atan2_special(y, x, a, b, xneg);
    } else {
        _Bool swap = (a > b);
        float k = sg_atan_kernel((swap ? b : a) / (swap ? a : b));
        float t = swap ? (SG_PIO2_HI + (SG_PIO2_LO - k)) : k;
        if (xneg != 0u) {
            t = SG_PI_HI + (SG_PI_LO - t);
        }
        r = ((sg_as_u32(y) >> 31) != 0u) ? -t : t;
    }
    return r;
}

/* ------------------------------------------------------------------ sqrt, pow */

float sg_sqrtf(float x)
{
    return SG_SQRTF(x);
}

#if !SG_HAVE_BUILTINS
/* The root of a positive finite x = M 2^(e - 23) (M the 24-bit significand, subnormals normalised):
 * with e' = e rounded down to even and M' = M 2^(e - e'), sqrt x = sqrt(M' 2^23) 2^(e'/2 - 23).
 * The root of M' 2^24 is taken one bit at a time (the schoolbook method in base 2: try bit b, keep it
 * while (q + b)^2 fits), 25 bits: 24 of the result and the rounding bit. A nonzero remainder means
 * more bits below, and a root is never exactly halfway between two floats, so rounding up when the
 * rounding bit is set is round to nearest even. The exponent field is added to the significand's
 * bits, so a rounding carry into the exponent is exact. */
static float sg_sqrtf_positive(uint32_t ux)
{
    uint32_t m = ux & 0x007fffffu;
    uint32_t e150 = ux >> 23; /* e + 150 for a normal x (e = field - 127): kept positive */
    uint32_t rem;
    uint32_t root = 0u;
    uint32_t twice = 0u; /* 2 root, in the scale of the bit being tried */
    uint32_t bit;
    if (e150 == 0u) {
        e150 = 1u;
        while (m < 0x00800000u) { /* subnormal: normalise */
            m <<= 1;
            e150 -= 1u;
        }
    } else {
        m |= 0x00800000u;
    }
    e150 += 23u; /* field + 23 = e + 150 (150 is even: e150 has e's parity) */
    rem = m << 1;
    if ((e150 & 1u) != 0u) {
        rem <<= 1;
    }
    for (bit = 0x01000000u; bit != 0u; bit >>= 1) {
        const uint32_t t = twice + bit;
        if (t <= rem) {
            twice = t + bit;
            rem -= t;
            root += bit;
        }
        rem <<= 1;
    }
    if (rem != 0u) {
        root += root & 1u;
    }
    /* (root >> 1) holds the implicit bit: field = 126 + floor(e / 2) + 1 */
    return sg_as_f32((root >> 1) + (((e150 >> 1) + 51u) << 23));
}

float sg_sqrtf_c99(float x)
{
    const uint32_t ux = sg_as_u32(x);
    float r;
    if (((ux & 0x7fffffffu) == 0u) || (ux == 0x7f800000u)) {
        r = x; /* +-0, +Inf */
    } else if ((ux & 0x7fffffffu) > 0x7f800000u) {
        r = x + x; /* NaN: quieted by the FPU, as VSQRT and sqrtss do */
    } else if ((ux >> 31) != 0u) {
        /* negative, -Inf: 0 / 0 (or NaN / NaN) at run time, the FPU's default NaN, as VSQRT and
         * sqrtss give (a constant 0.0f / 0.0f would be folded to one NaN for every target) */
        r = (x - x) / (x + (-x));
    } else {
        r = sg_sqrtf_positive(ux);
    }
    return r;
}
#endif

/* x^y = e^{y ln x} for x >= 0 (see sg_math.h for the special cases). */
/* Coefficients of sg_powf_fused (sg_math.h): log2(1+f)/f on [sqrt(1/2) - 1, sqrt(2) - 1] (degree 7,
 * absolute error of f P(f) 4.9e-8) and (2^r - 1)/r on [-1/2, 1/2] (degree 5, relative error of
 * 1 + r Q(r) 3.0e-9), float32 minimax fits rounded low order first. */
const float sg_powf_fused_tab[14] SG_TABLE(".sg_tables.sg_powf_fused_tab") = {
    -0x1.2a5f1ap-3f, 0x1.e50a6ap-3f, -0x1.0011d6p-2f, 0x1.25992ap-2f,
    -0x1.70baf6p-2f, 0x1.ec7b3ep-2f, -0x1.7155b8p-1f, 0x1.715472p+0f,
    0x1.417a9cp-13f, 0x1.5f0948p-10f, 0x1.3b2dd2p-7f, 0x1.c6af7ap-5f,
    0x1.ebfbdcp-3f, 0x1.62e43p-1f
};

/* sg_powf_tab (sg_math.h): rows {c, 1/c, log2 c} of the 32 intervals of z, then log2(1+r)/r =
 * a0 + r (a1 + r a2) and (2^(u/32) - 1)/u = b0 + u (b1 + u b2) (tools: docs/math.md). */
const float sg_powf_tab_log[SG_POWF_TAB_N][3] SG_TABLE(".sg_tables.sg_powf_tab_log") = {
    {0x1.6ap-1f, 0x1.6a13cep+0f, -0x1.001434p-1f},
    {0x1.72p-1f, 0x1.623fa8p+0f, -0x1.dfdd8ap-2f},
    {0x1.7ap-1f, 0x1.5ac056p+0f, -0x1.c04386p-2f},
    {0x1.82p-1f, 0x1.539094p+0f, -0x1.a152f2p-2f},
    {0x1.8ap-1f, 0x1.4cab88p+0f, -0x1.8304dap-2f},
    {0x1.92p-1f, 0x1.460cbcp+0f, -0x1.6552b4p-2f},
    {0x1.9ap-1f, 0x1.3fb014p+0f, -0x1.48365ep-2f},
    {0x1.a2p-1f, 0x1.3991c2p+0f, -0x1.2baa0cp-2f},
    {0x1.aap-1f, 0x1.33ae46p+0f, -0x1.0fa848p-2f},
    {0x1.b2p-1f, 0x1.2e025cp+0f, -0x1.e857d4p-3f},
    {0x1.bap-1f, 0x1.288b02p+0f, -0x1.b26024p-3f},
    {0x1.c2p-1f, 0x1.234568p+0f, -0x1.7d604ap-3f},
    {0x1.cap-1f, 0x1.1e2ef4p+0f, -0x1.494f86p-3f},
    {0x1.d2p-1f, 0x1.194538p+0f, -0x1.162594p-3f},
    {0x1.dap-1f, 0x1.1485fp+0f, -0x1.c7b528p-4f},
    {0x1.e2p-1f, 0x1.0fef02p+0f, -0x1.64ce26p-4f},
    {0x1.eap-1f, 0x1.0b7e6ep+0f, -0x1.0387fp-4f},
    {0x1.f2p-1f, 0x1.07326p+0f, -0x1.47aa08p-5f},
    {0x1.fap-1f, 0x1.03091cp+0f, -0x1.16a21ep-6f},
    {0x1.028p+0f, 0x1.fb0c62p-1f, 0x1.cb6c3ap-7f},
    {0x1.0ap+0f, 0x1.ecc07cp-1f, 0x1.c4dfacp-5f},
    {0x1.12p+0f, 0x1.de5d6ep-1f, 0x1.918a16p-4f},
    {0x1.1ap+0f, 0x1.d0cb58p-1f, 0x1.1dcd1ap-3f},
    {0x1.22p+0f, 0x1.c3f8fp-1f, 0x1.70742ep-3f},
    {0x1.2ap+0f, 0x1.b7d6c4p-1f, 0x1.c0db6cp-3f},
    {0x1.32p+0f, 0x1.ac5702p-1f, 0x1.0790aep-2f},
    {0x1.3ap+0f, 0x1.a16d4p-1f, 0x1.2db11p-2f},
    {0x1.42p+0f, 0x1.970e5p-1f, 0x1.52dbep-2f},
    {0x1.4ap+0f, 0x1.8d3018p-1f, 0x1.771d2cp-2f},
    {0x1.52p+0f, 0x1.83c978p-1f, 0x1.9a8024p-2f},
    {0x1.5ap+0f, 0x1.7ad22p-1f, 0x1.bd0f2ep-2f},
    {0x1.62p+0f, 0x1.724288p-1f, 0x1.ded3fep-2f}
};
const float sg_powf_tab_poly[6] SG_TABLE(".sg_tables.sg_powf_tab_poly") = {0x1.715476p+0f, -0x1.715daep-1f, 0x1.ec89cap-2f, 0x1.62e43p-6f, 0x1.ebfce6p-13f, 0x1.c6b186p-20f};
/* bits of 2^(j/32), j = 0 .. 31 (float32, round to nearest) */
const uint32_t sg_powf_tab_exp2[SG_POWF_TAB_N] SG_TABLE(".sg_tables.sg_powf_tab_exp2") = {
    0x3f800000u, 0x3f82cd87u, 0x3f85aac3u, 0x3f88980fu, 0x3f8b95c2u, 0x3f8ea43au, 0x3f91c3d3u, 0x3f94f4f0u,
    0x3f9837f0u, 0x3f9b8d3au, 0x3f9ef532u, 0x3fa27043u, 0x3fa5fed7u, 0x3fa9a15bu, 0x3fad583fu, 0x3fb123f6u,
    0x3fb504f3u, 0x3fb8fbafu, 0x3fbd08a4u, 0x3fc12c4du, 0x3fc5672au, 0x3fc9b9beu, 0x3fce248cu, 0x3fd2a81eu,
    0x3fd744fdu, 0x3fdbfbb8u, 0x3fe0ccdfu, 0x3fe5b907u, 0x3feac0c7u, 0x3fefe4bau, 0x3ff5257du, 0x3ffa83b3u
};

/* sg_logf_tab (sg_math.h): rows {c, 1/c, ln c}, the intervals of sg_powf_tab_log but c = 1 in the
 * one holding 1 (ln c = 0 there: no cancellation near x = 1). */
const float sg_logf_tab_rows[SG_POWF_TAB_N][3] SG_TABLE(".sg_tables.sg_logf_tab_rows") = {
    {0x1.6ap-1f, 0x1.6a13cep+0f, -0x1.63003p-2f},
    {0x1.72p-1f, 0x1.623fa8p+0f, -0x1.4c9e0ap-2f},
    {0x1.7ap-1f, 0x1.5ac056p+0f, -0x1.36b678p-2f},
    {0x1.82p-1f, 0x1.539094p+0f, -0x1.214456p-2f},
    {0x1.8ap-1f, 0x1.4cab88p+0f, -0x1.0c42d6p-2f},
    {0x1.92p-1f, 0x1.460cbcp+0f, -0x1.ef5adep-3f},
    {0x1.9ap-1f, 0x1.3fb014p+0f, -0x1.c6ffbcp-3f},
    {0x1.a2p-1f, 0x1.3991c2p+0f, -0x1.9f6c4p-3f},
    {0x1.aap-1f, 0x1.33ae46p+0f, -0x1.7898d8p-3f},
    {0x1.b2p-1f, 0x1.2e025cp+0f, -0x1.527e5ep-3f},
    {0x1.bap-1f, 0x1.288b02p+0f, -0x1.2d161p-3f},
    {0x1.c2p-1f, 0x1.234568p+0f, -0x1.08598cp-3f},
    {0x1.cap-1f, 0x1.1e2ef4p+0f, -0x1.c8858p-4f},
    {0x1.d2p-1f, 0x1.194538p+0f, -0x1.8197e2p-4f},
    {0x1.dap-1f, 0x1.1485fp+0f, -0x1.3bdf5ap-4f},
    {0x1.e2p-1f, 0x1.0fef02p+0f, -0x1.eea31cp-5f},
    {0x1.eap-1f, 0x1.0b7e6ep+0f, -0x1.67c95p-5f},
    {0x1.f2p-1f, 0x1.07326p+0f, -0x1.c63d2ep-6f},
    {0x1.fap-1f, 0x1.03091cp+0f, -0x1.82448ap-7f},
    {0x1.0p+0f, 0x1.0p+0f, 0.0f},
    {0x1.0ap+0f, 0x1.ecc07cp-1f, 0x1.39e87cp-5f},
    {0x1.12p+0f, 0x1.de5d6ep-1f, 0x1.16536ep-4f},
    {0x1.1ap+0f, 0x1.d0cb58p-1f, 0x1.8c345ep-4f},
    {0x1.22p+0f, 0x1.c3f8fp-1f, 0x1.fec914p-4f},
    {0x1.2ap+0f, 0x1.b7d6c4p-1f, 0x1.371fc2p-3f},
    {0x1.32p+0f, 0x1.ac5702p-1f, 0x1.6d60fep-3f},
    {0x1.3ap+0f, 0x1.a16d4p-1f, 0x1.a23bc2p-3f},
    {0x1.42p+0f, 0x1.970e5p-1f, 0x1.d5c216p-3f},
    {0x1.4ap+0f, 0x1.8d3018p-1f, 0x1.04025ap-2f},
    {0x1.52p+0f, 0x1.83c978p-1f, 0x1.1c898cp-2f},
    {0x1.5ap+0f, 0x1.7ad22p-1f, 0x1.347ddap-2f},
    {0x1.62p+0f, 0x1.724288p-1f, 0x1.4be5fap-2f}
};

float sg_powf_pos(float x, float y)
{
    if ((y == 0.0f) || (x == 1.0f)) {
        return 1.0f;
    }
    if (x < 0.0f) {
        return sg_nan();
    }
    return sg_expf(y * sg_logf(x));
}

uint32_t sg_crc32(const void *data, uint32_t bytes, uint32_t crc)
{
    const unsigned char *p = (const unsigned char *)data;
    uint32_t c = ~crc;
    uint32_t i;
    uint32_t k;
    for (i = 0u; i < bytes; ++i) {
        c ^= (uint32_t)p[i];
        for (k = 0u; k < 8u; ++k) {
            c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
        }
    }
    return ~c;
}
