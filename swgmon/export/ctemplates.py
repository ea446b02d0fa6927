"""C99 sources of the embedded stage (templates filled by :mod:`.cgen`).

The arithmetic is :mod:`.reference` op for op (same float32 operations in
the same order); compile without floating-point contraction (``-ffp-contract=off``) and
without ``-ffast-math``, so that no multiply-add is fused and no sum reassociated.
No dynamic allocation: the window state is a caller-owned struct (static or on the stack).
"""

HEADER = r"""/* swg_monitor.h - the condition monitor's per-window stage (swgsim-export).
 *
 * Data set {dataset}, gear {gear} (its normal behaviour at commissioning), classifier trained on
 * gears {train_gears}. Generated code: do not edit; re-export instead.
 *
 * Interface
 * ---------
 * A window is SWG_N_T samples at SWG_FS_HZ Hz of the five bridges s0..s4 [mV/V] and the
 * input angle phi [rad] (motor encoder, unwrapped, measured from the window's first
 * sample: phi = 0 there; for a steady window phi = 2 pi n t / 60 at n rpm). Feed it sample
 * by sample (no window buffer is kept: per bridge the stage accumulates the single-bin
 * DFTs of the orders and the energy, block by block of SWG_BLOCK samples):
 *
 *     swg_state_t st;              // caller-owned: static or stack, sizeof = SWG_STATE_BYTES
 *     swg_begin(&st);
 *     for (t = 0; t < SWG_N_T; t++) swg_push(&st, x_t, phi_t);   // x_t: float[5] [mV/V]
 *     cls = swg_end(&st, op, efficiency, features, &p_healthy);
 *
 * op        operating point of the window: row of SWG_OP_POINTS (desired input speed
 *           [rpm], output torque [N m]); swg_op_index() finds it.
 * efficiency  mean P_out / mean P_in of the window [-].
 * features  float[SWG_N_FEATURES] or NULL: per bridge the offset [mV/V], the amplitudes
 *           of WG harmonics 1..SWG_N_HARMONICS [mV/V] and log10 of the residual RMS
 *           [log10 mV/V]; then the efficiency (as learn.inputs.health.feature_names).
 * p_healthy float* or NULL: the forest's vote share of class 0 (healthy) [-].
 * returns   the class index (SWG_CLASS_NAMES), or a negative SWG_ERR_* code.
 *
 * Memory: swg_state_t (SWG_STATE_BYTES) and about 1 kB of stack in swg_end; constant
 * tables in flash (normal equations per speed, the normal behaviour per operating point, the
 * forest). The normal behaviour (mean, 1/std of every feature per operating point) is the gear's
 * own, set at commissioning: swg_end_with() takes it from RAM instead (e.g. computed on
 * the device or written to a flash page after commissioning).
 */
#ifndef SWG_MONITOR_H
#define SWG_MONITOR_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {{
#endif

#define SWG_N_T {n_t}                 /* samples per window */
#define SWG_FS_HZ {fs_hz:.1f}f          /* sample rate [Hz] */
#define SWG_N_BRIDGES 5
#define SWG_N_HARMONICS {n_harmonics}          /* WG harmonics h (1 + 1/N), N = {ratio:g} */
#define SWG_N_NUISANCE {n_nuisance}  /* orders {nuisance} of the input angle (fitted, dropped) */
#define SWG_N_ORDERS (SWG_N_HARMONICS + SWG_N_NUISANCE)
#define SWG_N_BASIS (1 + 2 * SWG_N_ORDERS)
#define SWG_BLOCK {block}                 /* samples per float32 partial sum */
#define SWG_N_FEATURES {n_features}           /* 5 (H + 2) + 1 */
#define SWG_N_INPUTS (SWG_N_FEATURES + 2) /* classifier inputs: int16 z-scores, speed, torque */
#define SWG_Z_SCALE {z_scale:.1f}f  /* int16 input = floor(z * SWG_Z_SCALE + 0.5), clipped */
#define SWG_N_OPS {n_ops}
#define SWG_N_SPEEDS {n_speeds}
#define SWG_N_CLASSES {n_classes}

#define SWG_ERR_LENGTH (-2)   /* the window did not hold SWG_N_T samples */
#define SWG_ERR_OP (-3)       /* op outside 0..SWG_N_OPS-1 */

/* Operating points (desired input speed [rpm], output torque [N m]) of the normal behaviour. */
extern const float SWG_OP_POINTS[SWG_N_OPS][2];
/* Class names, index = swg_end's return value; 0 is healthy. */
extern const char *const SWG_CLASS_NAMES[SWG_N_CLASSES];

#define SWG_NB (((SWG_N_BASIS + 3) / 4) * 4)   /* basis row padded to groups of 4 */

typedef struct {{
    float tot[SWG_N_BRIDGES][SWG_N_BASIS + 1];   /* totals: DFTs b, then energy */
    float comp[SWG_N_BRIDGES][SWG_N_BASIS + 1];  /* Kahan compensation of the totals */
    float yb[SWG_N_BRIDGES][SWG_BLOCK];          /* the block's samples minus x0 [mV/V] */
    float bb[SWG_BLOCK][SWG_NB];                 /* the block's basis rows */
    float x0[SWG_N_BRIDGES];                     /* first sample (subtracted) [mV/V] */
    int32_t n;                                   /* samples pushed */
}} swg_state_t;

#define SWG_STATE_BYTES ((int)sizeof(swg_state_t))

/* The gear's normal behaviour: mean and 1 / standard deviation per operating point and feature. */
typedef struct {{
    float mean[SWG_N_OPS][SWG_N_FEATURES];
    float inv_std[SWG_N_OPS][SWG_N_FEATURES];
}} swg_normal_t;

extern const swg_normal_t SWG_NORMAL;   /* gear {gear}'s, in flash */

void swg_begin(swg_state_t *st);
void swg_push(swg_state_t *st, const float x[SWG_N_BRIDGES], float phi_rad);
int32_t swg_end(swg_state_t *st, int32_t op, float efficiency, float *features,
                float *p_healthy);
int32_t swg_end_with(swg_state_t *st, const swg_normal_t *normal, int32_t op,
                     float efficiency, float *features, float *p_healthy);
/* Row of SWG_OP_POINTS of (rpm, N m), or SWG_ERR_OP. */
int32_t swg_op_index(float n_in_rpm, float t_out_nm);
/* One whole window: x row-major [5][n_t] [mV/V], phi [n_t] [rad]; features, p_healthy
 * as swg_end (state on the stack: about SWG_STATE_BYTES). */
int32_t swg_run_window(const float *x, const float *phi, int32_t n_t, int32_t op,
                       float efficiency, float *features, float *p_healthy);

#ifdef __cplusplus
}}
#endif

#endif /* SWG_MONITOR_H */
"""

SOURCE_TEMPLATE = r"""/* swg_monitor.c - the condition monitor's per-window stage (swgsim-export).
 * The arithmetic of swgmon/export/reference.py, op for op; compile with -ffp-contract=off
 * (no fused multiply-add) and without -ffast-math. See swg_monitor.h and docs/EXPORT.md.
 */
#include <math.h>
#include <stddef.h>
#include "swg_monitor.h"
#include "swg_tables.h"
#include "swg_model.h"

#define P SWG_N_BASIS
#define H SWG_N_HARMONICS

/* A product kept apart from the sum it feeds: on Cortex-M4 a VMUL + VADD pair costs 2
 * cycles where the VMLA GCC would fuse them into costs 3 (the same rounding either way:
 * VMLA is not fused). */
#if defined(__arm__) && defined(__GNUC__)
#define SWG_KEEP(x) __asm__("" : "+t"(x))
#else
#define SWG_KEEP(x) ((void)0)
#endif

static float mul(float a, float b)
{{
    float p = a * b;
    SWG_KEEP(p);
    return p;
}}

/* floor v, exact for |v| < 2^31 (no library call). */
static float floor32(float v)
{{
    const float t = (float)(int32_t)v;
    return t > v ? t - 1.0f : t;
}}

/* cos a, sin a: quadrant reduction to |r| <= pi/4, Taylor polynomials. */
static void sincos32(float a, float *c_out, float *s_out)
{{
    const float q = floor32(a * SWG_TWO_OVER_PI + 0.5f);
    const float r = (a - q * SWG_PIO2_HI) - q * SWG_PIO2_LO;
    const float r2 = r * r;
    const float s = r + r * r2 * (SWG_S1 + r2 * (SWG_S2 + r2 * (SWG_S3 + r2 * SWG_S4)));
    const float c = 1.0f + r2 * (SWG_C1 + r2 * (SWG_C2 + r2 * (SWG_C3 + r2 * (SWG_C4
                    + r2 * SWG_C5))));
    switch ((int32_t)q & 3) {{
    case 0: *c_out = c; *s_out = s; break;
    case 1: *c_out = -s; *s_out = c; break;
    case 2: *c_out = -c; *s_out = -s; break;
    default: *c_out = s; *s_out = -c; break;
    }}
}}

/* log10 y, y > 0: frexp, then 2 atanh((m - 1) / (m + 1)) by its series. */
static float log10_32(float y)
{{
    int e;
    float m = frexpf(y, &e);
    if (m < SWG_SQRT_HALF) {{
        m = m * 2.0f;
        e = e - 1;
    }}
    const float s = (m - 1.0f) / (m + 1.0f);
    const float s2 = s * s;
    const float series = s * (SWG_L0 + s2 * (SWG_L1 + s2 * (SWG_L2 + s2 * (SWG_L3
                         + s2 * SWG_L4))));
    return ((float)e * SWG_LN2 + series) * SWG_INV_LN10;
}}

/* The basis at input angle phi: 1, cos of the orders, sin of the orders. */
static void basis(float phi, float B[SWG_NB])
{{
    float c1, s1, cb, sb, c, s;
    float pc[SWG_NUIS_MAX], ps[SWG_NUIS_MAX];
    int32_t h, k;
    sincos32(phi * SWG_WG_ORDER, &c1, &s1);
    B[0] = 1.0f;
    c = c1;
    s = s1;
    B[1] = c;
    B[1 + SWG_N_ORDERS] = s;
#pragma GCC unroll 16
    for (h = 1; h < H; h++) {{
        const float cn = mul(c, c1) - mul(s, s1);
        const float sn = mul(s, c1) + mul(c, s1);
        c = cn;
        s = sn;
        B[1 + h] = c;
        B[1 + SWG_N_ORDERS + h] = s;
    }}
    sincos32(phi * SWG_NUIS_BASE, &cb, &sb);
    pc[0] = cb;
    ps[0] = sb;
#pragma GCC unroll 16
    for (k = 1; k < SWG_NUIS_MAX; k++) {{
        pc[k] = mul(pc[k - 1], cb) - mul(ps[k - 1], sb);
        ps[k] = mul(ps[k - 1], cb) + mul(pc[k - 1], sb);
    }}
#pragma GCC unroll 16
    for (k = 0; k < SWG_N_NUISANCE; k++) {{
        B[1 + H + k] = pc[SWG_NUIS_MULT[k] - 1];
        B[1 + SWG_N_ORDERS + H + k] = ps[SWG_NUIS_MULT[k] - 1];
    }}
    for (k = P; k < SWG_NB; k++) {{
        B[k] = 0.0f;
    }}
}}

/* Sums over the block's m samples, added into the totals (Kahan). Per bridge and basis
 * column: s = sum_t y_t B_tk from 0 in sample order; the five bridges and four columns
 * at a time in registers (each sample's four basis values loaded once). */
static void block_sums(swg_state_t *st, int32_t m)
{{
    float s[SWG_N_BRIDGES][SWG_NB + 1];
    int32_t ch, k, t;
    for (k = 0; k < SWG_NB; k += 4) {{
{kernel}
    }}
    for (ch = 0; ch < SWG_N_BRIDGES; ch++) {{
        const float *y = st->yb[ch];
        float e = 0.0f;
        for (t = 0; t < m; t++) {{
            e += mul(y[t], y[t]);
        }}
        s[ch][P] = e;
        for (k = 0; k <= P; k++) {{
            const float d = s[ch][k] - st->comp[ch][k];
            const float u = st->tot[ch][k] + d;
            st->comp[ch][k] = (u - st->tot[ch][k]) - d;
            st->tot[ch][k] = u;
        }}
    }}
}}

void swg_begin(swg_state_t *st)
{{
    int32_t ch, k;
    for (ch = 0; ch < SWG_N_BRIDGES; ch++) {{
        for (k = 0; k <= P; k++) {{
            st->tot[ch][k] = 0.0f;
            st->comp[ch][k] = 0.0f;
        }}
        st->x0[ch] = 0.0f;
    }}
    st->n = 0;
}}

void swg_push(swg_state_t *st, const float x[SWG_N_BRIDGES], float phi_rad)
{{
    const int32_t t = st->n % SWG_BLOCK;
    int32_t ch;
    basis(phi_rad, st->bb[t]);
    if (st->n == 0) {{
        for (ch = 0; ch < SWG_N_BRIDGES; ch++) {{
            st->x0[ch] = x[ch];
        }}
    }}
    for (ch = 0; ch < SWG_N_BRIDGES; ch++) {{
        st->yb[ch][t] = x[ch] - st->x0[ch];
    }}
    st->n++;
    if (t == SWG_BLOCK - 1) {{
        block_sums(st, SWG_BLOCK);
    }}
}}

/* out_i = sum_j m_ij v_j, j ascending, of a symmetric P x P matrix stored as its upper
 * triangle row by row, read once in storage order: row r gives out_r its terms j >= r
 * (after the terms j < r that rows 0..r-1 gave it) and out_j, j > r, its term j' = r. */
static void sym_matvec(const float *m, const float *v, float *out)
{{
    int32_t r, j, idx = 0;
    for (r = 0; r < P; r++) {{
        out[r] = 0.0f;
    }}
    for (r = 0; r < P; r++) {{
        const float vr = v[r];
        float a = out[r] + mul(m[idx], vr);
        idx++;
        for (j = r + 1; j < P; j++) {{
            const float mrj = m[idx];
            a += mul(mrj, v[j]);
            out[j] += mul(mrj, vr);
            idx++;
        }}
        out[r] = a;
    }}
}}

/* Features of one bridge from its totals (reference.features32). */
static void bridge_features(const float *tot, float x0, const float *ginv, const float *gram,
                            float *f)
{{
    float c[P], gc[P];
    float cb = 0.0f, cgc = 0.0f, ms;
    int32_t i;
    sym_matvec(ginv, tot, c);
    sym_matvec(gram, c, gc);
    for (i = 0; i < P; i++) {{
        cb += c[i] * tot[i];
        cgc += c[i] * gc[i];
    }}
    ms = ((tot[P] - 2.0f * cb) + cgc) / (float)SWG_N_T;
    if (ms < 0.0f) {{
        ms = 0.0f;
    }}
    f[0] = c[0] + x0;
    for (i = 0; i < H; i++) {{
        const float cc = c[1 + i], ss = c[1 + SWG_N_ORDERS + i];
        f[1 + i] = sqrtf(cc * cc + ss * ss);
    }}
    f[H + 1] = log10_32(sqrtf(ms) + SWG_REST_FLOOR);
}}

int32_t swg_end_with(swg_state_t *st, const swg_normal_t *normal, int32_t op,
                     float efficiency, float *features, float *p_healthy)
{{
    float f[SWG_N_FEATURES];
    float votes[SWG_N_CLASSES];
    int16_t q[SWG_N_INPUTS];
    int32_t ch, k, best = -1;
    float best_votes = 0.0f;
    if (st->n % SWG_BLOCK != 0) {{
        block_sums(st, st->n % SWG_BLOCK);  /* the last, partial block (once: then begin) */
    }}
    if (st->n != SWG_N_T) {{
        return SWG_ERR_LENGTH;
    }}
    if (op < 0 || op >= SWG_N_OPS) {{
        return SWG_ERR_OP;
    }}
    for (ch = 0; ch < SWG_N_BRIDGES; ch++) {{
        const int32_t s = SWG_OP_SPEED[op];
        bridge_features(st->tot[ch], st->x0[ch], SWG_G_INV[s], SWG_GRAM[s],
                        &f[ch * (H + 2)]);
    }}
    f[SWG_N_FEATURES - 1] = efficiency;
    for (k = 0; k < SWG_N_FEATURES; k++) {{
        const float z = (f[k] - normal->mean[op][k]) * normal->inv_std[op][k];
        float v = floor32(z * SWG_Z_SCALE + 0.5f);
        if (v > 32767.0f) {{
            v = 32767.0f;
        }} else if (v < -32767.0f) {{
            v = -32767.0f;
        }}
        q[k] = (int16_t)v;
        if (features != NULL) {{
            features[k] = f[k];
        }}
    }}
    q[SWG_N_FEATURES] = SWG_OP_INPUTS[op][0];
    q[SWG_N_FEATURES + 1] = SWG_OP_INPUTS[op][1];
    swg_forest_predict_proba(q, SWG_N_INPUTS, votes, SWG_N_CLASSES);
    for (k = 0; k < SWG_N_CLASSES; k++) {{  /* emlearn's eml_trees_predict: first maximum */
        if (votes[k] > best_votes) {{
            best = k;
            best_votes = votes[k];
        }}
    }}
    if (p_healthy != NULL) {{
        *p_healthy = votes[0];
    }}
    return best;
}}

int32_t swg_end(swg_state_t *st, int32_t op, float efficiency, float *features,
                float *p_healthy)
{{
    return swg_end_with(st, &SWG_NORMAL, op, efficiency, features, p_healthy);
}}

int32_t swg_op_index(float n_in_rpm, float t_out_nm)
{{
    int32_t k;
    for (k = 0; k < SWG_N_OPS; k++) {{
        if (SWG_OP_POINTS[k][0] == n_in_rpm && SWG_OP_POINTS[k][1] == t_out_nm) {{
            return k;
        }}
    }}
    return SWG_ERR_OP;
}}

int32_t swg_run_window(const float *x, const float *phi, int32_t n_t, int32_t op,
                       float efficiency, float *features, float *p_healthy)
{{
    swg_state_t st;
    float xt[SWG_N_BRIDGES];
    int32_t t, ch;
    swg_begin(&st);
    for (t = 0; t < n_t; t++) {{
        for (ch = 0; ch < SWG_N_BRIDGES; ch++) {{
            xt[ch] = x[ch * n_t + t];
        }}
        swg_push(&st, xt, phi[t]);
    }}
    return swg_end(&st, op, efficiency, features, p_healthy);
}}
"""


def block_kernel(n_bridges: int = 5, n_cols: int = 4) -> str:
    """The register-blocked body of ``block_sums`` (bridges x columns accumulators)."""
    ind = " " * 8
    acc = [f"a{c}{j}" for c in range(n_bridges) for j in range(n_cols)]
    lines = [ind + "float " + ", ".join(f"{a} = 0.0f" for a in acc[i:i + 5]) + ";"
             for i in range(0, len(acc), 5)]
    lines.append(ind + "#pragma GCC unroll 2")
    lines.append(ind + "for (t = 0; t < m; t++) {{")
    lines.append(ind + "    const float *b = &st->bb[t][k];")
    lines.append(ind + "    const float " + ", ".join(f"b{j} = b[{j}]" for j in range(n_cols))
                 + ";")
    for c in range(n_bridges):
        lines.append(ind + f"    const float v{c} = st->yb[{c}][t];")
        lines += [ind + f"    a{c}{j} += mul(v{c}, b{j});" for j in range(n_cols)]
    lines.append(ind + "}}")
    lines += [ind + f"s[{c}][k + {j}] = a{c}{j};" for c in range(n_bridges)
              for j in range(n_cols)]
    return "\n".join(lines)


SOURCE = SOURCE_TEMPLATE.replace("{kernel}", block_kernel())
