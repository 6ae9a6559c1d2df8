/* C kernels of robotplan (float32, one thread), built by setup.py, loaded by robotplan/base/native.py
 * (the system's C compiler, ctypes); see its docstring for why, and
 * docs/experiments.md#native-kernels for the timings.
 *
 * SDF encoder convolutions, over a batch of M images (NCHW):
 *   rp_conv_forward   y = ReLU(conv(x, w, stride) + b) over the input channels listed in
 *                     `in_ch` (the others are zero: dead channels of the previous layer),
 *                     and the sum of each output channel (which channels are live);
 *   rp_conv_backward  gx = conv_transposeᵀ(g masked by the ReLU outputs y > 0), between the
 *                     listed live output channels and the wanted input channels.
 * Vectorized along image rows, 8 floats per vector (GCC vector extensions: AVX2 + FMA where
 * the compiler is told so, SSE otherwise); each output pixel block keeps every output
 * channel's accumulator in registers, so an input vector loaded once feeds all of them.
 * Layers wider than MAXC run in groups of at most MAXC output channels over one staging.
 * Stride 2 reads column-deinterleaved copies of the input rows (stride 1 along the row), and
 * its transposed form computes the even and odd output columns together and interleaves them.
 *
 * Closed-form SDFs of circles, boxes and L-shapes with their gradients (robotplan/sdf):
 *   rp_render         on the grid X_h at S poses, with the body-frame coordinates;
 *   rp_shape_planes   at given body-frame points.
 */
#include <stdlib.h>
#include <math.h>
#include <string.h>

typedef float v8 __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));
typedef float v8u __attribute__((vector_size(32), aligned(4)));

#define LOAD(p) (*(const v8u *)(p))
#define STORE(p, v) (*(v8u *)(p) = (v))
#define MAXC 8   /* output channels per register block: wider layers run in groups of MAXC */
#define MAXCH 64 /* channels per layer handled here */
#define MAXK 16  /* kernel size */
#define BLOCK 32 /* the widest row block of the forward kernel (four vectors) */

static inline v8 relu8(v8 a) {
    v8 zero = {0};
    v8i on = a > zero;
    return (v8)((v8i)a & on);
}

static inline float hsum8(v8 a) {
    float s = 0.f;
    for (int i = 0; i < 8; ++i) s += a[i];
    return s;
}

/* Stage the input rows: scr[c][p][r][j] = x[in_ch[c]][r][S·j + p] (zero past the row end),
 * p < S the column phase; row stride RS, plane stride PS = rows · RS. */
static void stage_input(const float *x, int H, int W, int S, const int *in_ch, int nci,
                        float *scr, long RS, long PS) {
    const v8i even = {0, 2, 4, 6, 8, 10, 12, 14}, odd = {1, 3, 5, 7, 9, 11, 13, 15};
    for (int c = 0; c < nci; ++c) {
        const float *plane = x + (long)in_ch[c] * H * W;
        for (int r = 0; r < H; ++r) {
            const float *src = plane + (long)r * W;
            float *d0 = scr + (long)c * S * PS + (long)r * RS;
            if (S == 1) {
                memcpy(d0, src, sizeof(float) * W);
                memset(d0 + W, 0, sizeof(float) * (RS - W));
                continue;
            }
            float *d1 = d0 + PS;
            int j = 0;
            for (; 2 * j + 16 <= W; j += 8) {
                v8 a = LOAD(src + 2 * j), b = LOAD(src + 2 * j + 8);
                STORE(d0 + j, __builtin_shuffle(a, b, even));
                STORE(d1 + j, __builtin_shuffle(a, b, odd));
            }
            for (; j < RS; ++j) {
                d0[j] = 2 * j < W ? src[2 * j] : 0.f;
                d1[j] = 2 * j + 1 < W ? src[2 * j + 1] : 0.f;
            }
        }
    }
}

/* One forward kernel per output-channel count N, with NV vectors per row block (all N·NV
 * accumulators stay in registers). */
#define DEFINE_FORWARD(N, NV)                                                                 \
    static void forward_##N(const float *scr, int nci, int S, long RS, long PS, int K,      \
                            const float *w, const float *b, int Ho, int Wo, float *y,       \
                            float *sums, int relu) {                                        \
        const long KK = (long)K * K, wo_stride = (long)nci * KK;                            \
        const int block = 8 * NV;                                                           \
        long offset[MAXK]; /* where tap kx reads, relative to the row: no division inside */ \
        for (int kx = 0; kx < K; ++kx) offset[kx] = (kx % S) * PS + kx / S;                 \
        v8 total[N];                                                                        \
        float tail_total[N];                                                                \
        for (int o = 0; o < N; ++o) total[o] = (v8){0}, tail_total[o] = 0.f;                \
        for (int oy = 0; oy < Ho; ++oy) {                                                   \
            for (int x0 = 0; x0 < Wo; x0 += block) {                                        \
                v8 a[N][NV];                                                                \
                _Pragma("GCC unroll 8") for (int o = 0; o < N; ++o)                         \
                    _Pragma("GCC unroll 4") for (int v = 0; v < NV; ++v)                    \
                        a[o][v] = (v8){0} + b[o];                                           \
                for (int c = 0; c < nci; ++c) {                                             \
                    for (int ky = 0; ky < K; ++ky) {                                        \
                        const float *row = scr + (long)c * S * PS + (long)(oy * S + ky) * RS \
                                           + x0;                                            \
                        const float *wr = w + c * KK + ky * K;                              \
                        for (int kx = 0; kx < K; ++kx) {                                    \
                            const float *p = row + offset[kx];                              \
                            v8 s[NV];                                                       \
                            _Pragma("GCC unroll 4") for (int v = 0; v < NV; ++v)            \
                                s[v] = LOAD(p + 8 * v);                                     \
                            _Pragma("GCC unroll 8") for (int o = 0; o < N; ++o) {           \
                                float ww = wr[o * wo_stride + kx];                          \
                                _Pragma("GCC unroll 4") for (int v = 0; v < NV; ++v)        \
                                    a[o][v] += ww * s[v];                                   \
                            }                                                               \
                        }                                                                   \
                    }                                                                       \
                }                                                                           \
                int n = Wo - x0 < block ? Wo - x0 : block;                                  \
                for (int o = 0; o < N; ++o) {                                               \
                    float *dst = y + (long)o * Ho * Wo + (long)oy * Wo + x0;                \
                    float tmp[8 * NV];                                                      \
                    _Pragma("GCC unroll 4") for (int v = 0; v < NV; ++v) {                  \
                        v8 r = relu ? relu8(a[o][v]) : a[o][v];                             \
                        if (n == block) {                                                   \
                            STORE(dst + 8 * v, r);                                          \
                            total[o] += r;                                                  \
                        } else {                                                            \
                            STORE(tmp + 8 * v, r);                                          \
                        }                                                                   \
                    }                                                                       \
                    if (n < block)                                                          \
                        for (int i = 0; i < n; ++i) dst[i] = tmp[i], tail_total[o] += tmp[i]; \
                }                                                                           \
            }                                                                               \
        }                                                                                   \
        if (sums)                                                                           \
            for (int o = 0; o < N; ++o) sums[o] += hsum8(total[o]) + tail_total[o];         \
    }

DEFINE_FORWARD(1, 4)
DEFINE_FORWARD(2, 4)
DEFINE_FORWARD(3, 3) /* 24-pixel blocks: 0.73 ms for the first layer, against 0.89 (16), 1.08 (32) */
DEFINE_FORWARD(4, 2)
DEFINE_FORWARD(5, 2)
DEFINE_FORWARD(6, 2)
DEFINE_FORWARD(7, 1)
DEFINE_FORWARD(8, 1)

typedef void (*forward_fn)(const float *, int, int, long, long, int, const float *,
                           const float *, int, int, float *, float *, int);
static const forward_fn FORWARD[MAXC + 1] = {0,         forward_1, forward_2, forward_3,
                                             forward_4, forward_5, forward_6, forward_7,
                                             forward_8};

/* All N output channels of one staged image, in groups of at most MAXC (the register block):
 * w (N, nci, K, K), y (N, Ho, Wo); bias b (N,) or NULL for none, sums (N,) or NULL. */
static void forward_groups(const float *scr, int nci, int S, long RS, long PS, int K,
                           const float *w, const float *b, int N, int Ho, int Wo, float *y,
                           float *sums, int relu) {
    const float zero_b[MAXC] = {0};
    for (int o0 = 0; o0 < N; o0 += MAXC) {
        const int n = N - o0 < MAXC ? N - o0 : MAXC;
        FORWARD[n](scr, nci, S, RS, PS, K, w + (long)o0 * nci * K * K, b ? b + o0 : zero_b,
                   Ho, Wo, y + (long)o0 * Ho * Wo, sums ? sums + o0 : NULL, relu);
    }
}

/* x (M, Cx, H, W) → y (M, N, Ho, Wo) = ReLU(conv), Ho = (H − K) / S + 1; sums (N,) are added
 * to. w (N, nci, K, K): the weights of the listed input channels only. Returns 0, or −1 for
 * sizes it does not handle. */
int rp_conv_forward(const float *x, int M, int Cx, int H, int W, const int *in_ch, int nci,
                    const float *w, const float *b, int N, int K, int S, float *y,
                    float *sums) {
    if (N < 1 || N > MAXCH || nci < 1 || nci > MAXCH || (S != 1 && S != 2) || K > H || K > W
        || K > MAXK)
        return -1;
    for (int c = 0; c < nci; ++c)
        if (in_ch[c] < 0 || in_ch[c] >= Cx) return -1;
    const int Ho = (H - K) / S + 1, Wo = (W - K) / S + 1;
    const long RS = (Wo + BLOCK + K + 8 + 7) / 8 * 8; /* reads reach x0 + block + K */
    const long PS = (long)H * RS;
    float *scr = aligned_alloc(32, sizeof(float) * (nci * S * PS + 8));
    if (!scr) return -1;
    for (int m = 0; m < M; ++m) {
        stage_input(x + (long)m * Cx * H * W, H, W, S, in_ch, nci, scr, RS, PS);
        forward_groups(scr, nci, S, RS, PS, K, w, b, N, Ho, Wo, y + (long)m * N * Ho * Wo, sums,
                       1);
    }
    free(scr);
    return 0;
}

/* Stage the masked gradient: scr[c][P + r][P + j] = g[c][r][j] if y[live[c]][r][j] > 0,
 * zero elsewhere (a border of P zeros around it); row stride RS, plane stride PS. */
static void stage_masked(const float *g, const float *y, int Cy, const int *live, int ng,
                         int Ho, int Wo, int P, float *scr, long RS, long PS) {
    memset(scr, 0, sizeof(float) * ng * PS);
    (void)Cy;
    for (int c = 0; c < ng; ++c) {
        const float *gp = g + (long)c * Ho * Wo, *yp = y + (long)live[c] * Ho * Wo;
        for (int r = 0; r < Ho; ++r) {
            float *d = scr + (long)c * PS + (long)(P + r) * RS + P;
            const float *gr = gp + (long)r * Wo, *yr = yp + (long)r * Wo;
            int j = 0;
            for (; j + 8 <= Wo; j += 8) {
                v8 zero = {0};
                v8i on = LOAD(yr + j) > zero;
                STORE(d + j, (v8)((v8i)LOAD(gr + j) & on));
            }
            for (; j < Wo; ++j) d[j] = yr[j] > 0.f ? gr[j] : 0.f;
        }
    }
}

/* Stride 1: gx[i][r][j] = Σ_c Σ_ky,kx gpad[c][r + K−1−ky][j + K−1−kx] · w[c][i][ky][kx],
 * i.e. the forward kernel over the padded gradient with weights wt (N, ng, K, K) already
 * flipped and transposed by the caller. */

/* Stride 2, one kernel per input-channel count N: output row r = 2u + a; the even (c = 0)
 * and odd (c = 1) columns 2v + c of a block of 8 v are accumulated together:
 * gx[i][2u+a][2v+c] = Σ_o Σ_j Σ_q gpad[o][u − j + P][v − q + P] · w[o][i][a + 2j][c + 2q]. */
#define DEFINE_BACKWARD2(N)                                                                  \
    static void backward2_##N(const float *scr, int ng, long RS, long PS, int K, int P,     \
                              const float *w, long wo_stride, int H, int W, float *gx) {    \
        const long KK = (long)K * K;                                                        \
        const v8i lo = {0, 8, 1, 9, 2, 10, 3, 11}, hi = {4, 12, 5, 13, 6, 14, 7, 15};       \
        const int half = (W + 1) / 2;                                                       \
        for (int r = 0; r < H; ++r) {                                                       \
            const int u = r / 2, a = r % 2;                                                 \
            for (int v0 = 0; v0 < half; v0 += 8) {                                          \
                v8 e[N], d[N];                                                              \
                _Pragma("GCC unroll 8") for (int i = 0; i < N; ++i) e[i] = d[i] = (v8){0};  \
                for (int o = 0; o < ng; ++o) {                                              \
                    for (int ky = a, j = 0; ky < K; ky += 2, ++j) {                         \
                        const float *row = scr + (long)o * PS + (long)(u - j + P) * RS      \
                                           + v0 + P;                                        \
                        const float *wr = w + o * wo_stride + ky * K;                       \
                        for (int kx = 0, q = 0; kx < K; kx += 2, ++q) {                     \
                            v8 s = LOAD(row - q);                                           \
                            _Pragma("GCC unroll 8") for (int i = 0; i < N; ++i)             \
                                e[i] += wr[i * KK + kx] * s;                                \
                            if (kx + 1 < K) {                                               \
                                _Pragma("GCC unroll 8") for (int i = 0; i < N; ++i)         \
                                    d[i] += wr[i * KK + kx + 1] * s;                        \
                            }                                                               \
                        }                                                                   \
                    }                                                                       \
                }                                                                           \
                const int n = W - 2 * v0 < 16 ? W - 2 * v0 : 16;                            \
                for (int i = 0; i < N; ++i) {                                               \
                    float *dst = gx + (long)i * H * W + (long)r * W + 2 * v0;               \
                    v8 x0 = __builtin_shuffle(e[i], d[i], lo);                              \
                    v8 x1 = __builtin_shuffle(e[i], d[i], hi);                              \
                    if (n == 16) {                                                          \
                        STORE(dst, x0);                                                     \
                        STORE(dst + 8, x1);                                                 \
                    } else {                                                                \
                        float tmp[16];                                                      \
                        STORE(tmp, x0);                                                     \
                        STORE(tmp + 8, x1);                                                 \
                        memcpy(dst, tmp, sizeof(float) * n);                                \
                    }                                                                       \
                }                                                                           \
            }                                                                               \
        }                                                                                   \
    }

DEFINE_BACKWARD2(1)
DEFINE_BACKWARD2(2)
DEFINE_BACKWARD2(3)
DEFINE_BACKWARD2(4)
DEFINE_BACKWARD2(5)
DEFINE_BACKWARD2(6)
DEFINE_BACKWARD2(7)
DEFINE_BACKWARD2(8)

typedef void (*backward2_fn)(const float *, int, long, long, int, int, const float *, long,
                             int, int, float *);
static const backward2_fn BACKWARD2[MAXC + 1] = {0,           backward2_1, backward2_2,
                                                 backward2_3, backward2_4, backward2_5,
                                                 backward2_6, backward2_7, backward2_8};

/* g (M, ng, Ho, Wo): the gradient at the layer's live output channels `live` (ng of the Cy
 * channels of its ReLU outputs y (M, Cy, Ho, Wo)); → gx (M, N, H, W), the gradient at the
 * wanted N input channels. Weights: stride 1, wt (N, ng, K, K) flipped and transposed; stride
 * 2, w (ng, N, K, K) as in the forward convolution. Returns 0, or −1 for sizes it does not
 * handle. */
int rp_conv_backward(const float *g, const float *y, int M, int Cy, const int *live, int ng,
                     int Ho, int Wo, const float *w, int N, int K, int S, int H, int W,
                     float *gx) {
    if (N < 1 || N > MAXCH || ng < 1 || ng > MAXCH || (S != 1 && S != 2) || K > MAXK
        || Ho != (H - K) / S + 1 || Wo != (W - K) / S + 1)
        return -1;
    for (int c = 0; c < ng; ++c)
        if (live[c] < 0 || live[c] >= Cy) return -1;
    if (S == 1) {
        const int P = K - 1;
        const long RS = (W + BLOCK + K + 8 + 7) / 8 * 8;
        const long PS = (long)(Ho + 2 * P) * RS;
        float *scr = aligned_alloc(32, sizeof(float) * (ng * PS + 8));
        if (!scr) return -1;
        for (int m = 0; m < M; ++m) {
            stage_masked(g + (long)m * ng * Ho * Wo, y + (long)m * Cy * Ho * Wo, Cy, live, ng,
                         Ho, Wo, P, scr, RS, PS);
            forward_groups(scr, ng, 1, RS, PS, K, w, NULL, N, H, W, gx + (long)m * N * H * W,
                           NULL, 0);
        }
        free(scr);
        return 0;
    }
    const int D = (K + 1) / 2, P = D - 1;
    const int half = (W + 1) / 2;
    const long RS = ((half + 8 + P + 8) + 7) / 8 * 8 + 8;
    const long rows = (H + 1) / 2 + P + 1;
    const long PS = rows * RS;
    if (Ho + P > rows) return -1;
    float *scr = aligned_alloc(32, sizeof(float) * (ng * PS + 8));
    if (!scr) return -1;
    for (int m = 0; m < M; ++m) {
        stage_masked(g + (long)m * ng * Ho * Wo, y + (long)m * Cy * Ho * Wo, Cy, live, ng, Ho,
                     Wo, P, scr, RS, PS);
        for (int i0 = 0; i0 < N; i0 += MAXC) {
            const int n = N - i0 < MAXC ? N - i0 : MAXC;
            BACKWARD2[n](scr, ng, RS, PS, K, P, w + (long)i0 * K * K, (long)N * K * K, H, W,
                         gx + ((long)m * N + i0) * H * W);
        }
    }
    free(scr);
    return 0;
}

/* ------------------------------------------------------------------ grid rendering
 * φ of a planar shape at S poses on the H × W grid X_h (cell centres x0 + (j + ½)·res,
 * y0 + (i + ½)·res), with its body-frame gradient (gx, gy) and, for a turning body, the
 * body-frame coordinates (px, py): what robotplan.functionals.dynamics.render_on_grid
 * computes with PyTorch, in one pass. Same closed forms as robotplan/sdf/shapes2d.py. */

/* Float selects and max/min vectorize only when NaNs and signed zeros may be ignored: for
 * the functions from here on (finite poses; a signed zero is multiplied by a sign of 0). */
#pragma GCC optimize("finite-math-only", "no-signed-zeros")

static inline float sign1(float v) { return (float)((v > 0.f) - (v < 0.f)); }

/* the box of half extents (hx, hy) centred at (cx, cy): φ, ∂φ/∂x, ∂φ/∂y (_box_sdf_and_grad) */
static inline void box_sdf(float px, float py, float cx, float cy, float hx, float hy,
                           float *phi, float *gx, float *gy) {
    const float dx = px - cx, dy = py - cy;
    const float qx = fabsf(dx) - hx, qy = fabsf(dy) - hy;
    const float ox = qx > 0.f ? qx : 0.f, oy = qy > 0.f ? qy : 0.f;
    const float out = sqrtf(ox * ox + oy * oy);
    const float inv = 1.f / (out > 1e-30f ? out : 1e-30f);
    const float deepest = qx > qy ? qx : qy;
    const int inner = deepest <= 0.f, x_face = (qx > qy) & inner; /* & and ^: no branches */
    *gx = (ox * inv + (float)x_face) * sign1(dx);
    *gy = (oy * inv + (float)(inner ^ x_face)) * sign1(dy);
    *phi = out + (deepest < 0.f ? deepest : 0.f);
}

static inline void circle_pixel(float px, float py, const float *q, float *f, float *a,
                                float *b) {
    const float norm = sqrtf(px * px + py * py + 1e-30f) - 1e-15f; /* safe_hypot */
    const float inv = 1.f / (norm > 1e-12f ? norm : 1e-12f);
    *f = norm - q[0], *a = px * inv, *b = py * inv;
}

static inline void box_pixel(float px, float py, const float *q, float *f, float *a,
                             float *b) {
    box_sdf(px, py, 0.f, 0.f, q[0], q[1], f, a, b);
}

/* a if m else b, for m 0 or 1: arithmetic, so that the loop stays free of branches */
static inline float pick(float m, float a, float b) { return m * a + (1.f - m) * b; }

/* One box over a row of body-frame points (a loop simple enough to vectorize). */
static void box_row(const float *restrict px, const float *restrict py, int W,
                    const float *restrict q, float *restrict f, float *restrict a,
                    float *restrict b) {
    const float cx = q[0], cy = q[1], hx = q[2], hy = q[3];
    for (int j = 0; j < W; ++j) box_sdf(px[j], py[j], cx, cy, hx, hy, f + j, a + j, b + j);
}

/* The L-shape over a row: its four boxes (bottom strip, left strip, bounding box, notch),
 * then outside the nearer strip, inside the larger of the bounding box and the negated
 * notch (LShape.sdf_and_grad_planes). `tmp`: 12·W floats. */
static void lshape_row(const float *restrict px, const float *restrict py, int W,
                       const float *restrict q, float *restrict f, float *restrict a,
                       float *restrict b, float *restrict tmp) {
    float *v[4], *u[4], *w[4];
    for (int k = 0; k < 4; ++k) {
        v[k] = tmp + 3 * k * W, u[k] = v[k] + W, w[k] = u[k] + W;
        box_row(px, py, W, q + 4 * k, v[k], u[k], w[k]);
    }
    const float *restrict v0 = v[0], *restrict v1 = v[1], *restrict v2 = v[2], *restrict v3 = v[3];
    const float *restrict u0 = u[0], *restrict u1 = u[1], *restrict u2 = u[2], *restrict u3 = u[3];
    const float *restrict w0 = w[0], *restrict w1 = w[1], *restrict w2 = w[2], *restrict w3 = w[3];
    for (int j = 0; j < W; ++j) {
        const float inside = (float)((v0[j] < v1[j] ? v0[j] : v1[j]) < 0.f);
        const float notch = (float)(v2[j] <= -v3[j]), left = (float)(v0[j] >= v1[j]);
        f[j] = pick(inside, pick(notch, -v3[j], v2[j]), pick(left, v1[j], v0[j]));
        a[j] = pick(inside, pick(notch, -u3[j], u2[j]), pick(left, u1[j], u0[j]));
        b[j] = pick(inside, pick(notch, -w3[j], w2[j]), pick(left, w1[j], w0[j]));
    }
}

/* One renderer per shape and output set (TURNING: px, py written too), each a single
 * branch-free row loop that vectorizes; cos_sin NULL: yaw 0. */
#define DEFINE_RENDER(NAME, PIXEL, TURNING)                                                   \
    static void NAME(const float *X, int S, int dofs, const float *cos_sin, int H, int W,     \
                     float x0, float y0, float res, const float *restrict q, float *phi,      \
                     float *gx, float *gy, float *px_out, float *py_out) {                    \
        for (int s = 0; s < S; ++s) {                                                         \
            const float c = cos_sin ? cos_sin[2 * s] : 1.f;                                   \
            const float sn = cos_sin ? cos_sin[2 * s + 1] : 0.f;                              \
            const float cx = X[s * dofs], cy = X[s * dofs + 1];                               \
            for (int i = 0; i < H; ++i) {                                                     \
                const float dy = y0 + ((float)i + 0.5f) * res - cy;                           \
                const long row = ((long)s * H + i) * W;                                       \
                float *restrict f = phi + row, *restrict a = gx + row, *restrict b = gy + row; \
                float *restrict u = TURNING ? px_out + row : NULL;                            \
                float *restrict v = TURNING ? py_out + row : NULL;                            \
                for (int j = 0; j < W; ++j) {                                                 \
                    const float dx = x0 + ((float)j + 0.5f) * res - cx;                       \
                    const float px = c * dx + sn * dy, py = c * dy - sn * dx;                 \
                    PIXEL(px, py, q, f + j, a + j, b + j);                                    \
                    if (TURNING) u[j] = px, v[j] = py;                                        \
                }                                                                             \
            }                                                                                 \
        }                                                                                     \
    }

DEFINE_RENDER(render_circle, circle_pixel, 0)
DEFINE_RENDER(render_box, box_pixel, 0)
DEFINE_RENDER(render_box_turning, box_pixel, 1)

/* The L-shape, row by row: body-frame coordinates first (into px_out, py_out when asked). */
static int render_lshape(const float *X, int S, int dofs, const float *cos_sin, int H, int W,
                         float x0, float y0, float res, const float *q, float *phi, float *gx,
                         float *gy, float *px_out, float *py_out) {
    float *tmp = malloc(sizeof(float) * 14 * (size_t)W);
    if (!tmp) return -1;
    float *restrict rx = tmp + 12 * W, *restrict ry = tmp + 13 * W;
    for (int s = 0; s < S; ++s) {
        const float c = cos_sin ? cos_sin[2 * s] : 1.f, sn = cos_sin ? cos_sin[2 * s + 1] : 0.f;
        const float cx = X[s * dofs], cy = X[s * dofs + 1];
        for (int i = 0; i < H; ++i) {
            const float dy = y0 + ((float)i + 0.5f) * res - cy;
            const long row = ((long)s * H + i) * W;
            float *restrict u = px_out ? px_out + row : rx, *restrict v = py_out ? py_out + row : ry;
            for (int j = 0; j < W; ++j) {
                const float dx = x0 + ((float)j + 0.5f) * res - cx;
                u[j] = c * dx + sn * dy, v[j] = c * dy - sn * dx;
            }
            lshape_row(u, v, W, q, phi + row, gx + row, gy + row, tmp);
        }
    }
    free(tmp);
    return 0;
}

typedef void (*render_fn)(const float *, int, int, const float *, int, int, float, float, float,
                          const float *, float *, float *, float *, float *, float *);

/* kind 0: circle, params = {radius}; 1: box, {hx, hy}; 2: L-shape, 4 boxes {cx, cy, hx, hy}
 * (bottom strip, left strip, bounding box, notch: lshape_boxes). X (S, dofs): x, y[, yaw];
 * cos_sin (S, 2) of the yaw, or NULL for yaw 0; px_out, py_out: the body-frame coordinates,
 * written where both are given. */
int rp_render(const float *X, int S, int dofs, const float *cos_sin, int H, int W, float x0,
              float y0, float res, int kind, const float *params, float *phi, float *gx,
              float *gy, float *px_out, float *py_out) {
    if (kind < 0 || kind > 2 || (dofs != 2 && dofs != 3)) return -1;
    const int turning = px_out != NULL && py_out != NULL; /* body-frame coordinates asked */
    if (kind == 2)
        return render_lshape(X, S, dofs, cos_sin, H, W, x0, y0, res, params, phi, gx, gy,
                             turning ? px_out : NULL, turning ? py_out : NULL);
    const render_fn fn = kind == 0 ? render_circle : turning ? render_box_turning : render_box;
    fn(X, S, dofs, cos_sin, H, W, x0, y0, res, params, phi, gx, gy, px_out, py_out);
    return 0;
}

/* φ and its body-frame gradient at n body-frame points (px, py): Shape2D.sdf_and_grad_planes
 * for the same shapes and parameters as rp_render. */
int rp_shape_planes(int kind, const float *params, long n, const float *px, const float *py,
                    float *phi, float *gx, float *gy) {
    if (kind < 0 || kind > 2) return -1;
    if (kind == 0) {
        for (long j = 0; j < n; ++j) circle_pixel(px[j], py[j], params, phi + j, gx + j, gy + j);
        return 0;
    }
    if (kind == 1) {
        for (long j = 0; j < n; ++j) box_pixel(px[j], py[j], params, phi + j, gx + j, gy + j);
        return 0;
    }
    enum { CHUNK = 256 };
    float tmp[12 * CHUNK];
    for (long j = 0; j < n; j += CHUNK) {
        const int m = n - j < CHUNK ? (int)(n - j) : CHUNK;
        lshape_row(px + j, py + j, m, params, phi + j, gx + j, gy + j, tmp);
    }
    return 0;
}
