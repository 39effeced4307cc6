/* exp_neg.h: exp(-x), fast for 0 <= x <= 1/2: the renderer's most frequent
 * transcendental (kernels/render_volume.h: urm takes one per quadrature point
 * for the interval's control and one per majorant segment for the front
 * factor). Compiled for the host too, so tests/test_cl_context.c checks the
 * device's values against the same formula and both against double
 * precision. */
#ifndef CLVR_EXP_NEG_H
#define CLVR_EXP_NEG_H

#include "clvr_shared.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#define CLVR_EXPF(x) expf(x)
#else
#define CLVR_EXPF(x) exp(x)
#endif

/* Nearly always x <= kappa / 2 there (kappa: the most majorant optical
 * depth between two quadrature points, 0.25 by default), where a degree-8
 * Taylor polynomial (truncation below 6e-9 on [0, 1/2], a tenth of an ulp)
 * in Estrin's form has a short dependency chain. The library's exp, with
 * its range reduction, took half of clvr_urm_segment's time on the 13k-tet
 * notch (perf, PoCL); with this the notch's urm frames are 11-16% faster.
 * Any other x (negative, larger, NaN): exp. */
CLVR_INLINE float clvr_exp_neg(float x)
{
    if (!(x >= 0.0f && x <= 0.5f)) return CLVR_EXPF(-x);
    const float x2 = x * x, x4 = x2 * x2;
    const float a01 = 1.0f - x, a23 = 0.5f - x * (1.0f / 6.0f);
    const float a45 = (1.0f / 24.0f) - x * (1.0f / 120.0f), a67 = (1.0f / 720.0f) - x * (1.0f / 5040.0f);
    const float b0 = a01 + x2 * a23, b1 = a45 + x2 * a67;
    return b0 + x4 * (b1 + x4 * (1.0f / 40320.0f));
}

#endif /* CLVR_EXP_NEG_H */
