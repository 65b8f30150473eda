/* Philox4x32 (Salmon, Moraes, Dror, Shaw 2011): a counter-based generator; 10 rounds for
 * simulation. The round count is a parameter only so the harness can check the published
 * 7-round known answers too. */
#define PHILOX_M0 0xD2511F53u
#define PHILOX_M1 0xCD9E8D57u
#define PHILOX_W0 0x9E3779B9u
#define PHILOX_W1 0xBB67AE85u

/* Both halves of each 32x32 product from one 64-bit multiply: PoCL's mul_hi builds it from
 * 16-bit pieces (it was most of the cost of a scattering event), and a GPU compiles this
 * form to its native high multiply too. The state is four scalars, not a uint4: as a
 * vector every round extracted and inserted lanes, a quarter of a scattering event. */
LSQT_INLINE uint4 philox4x32_rounds(uint4 c, uint2 k, int rounds)
{
    uint c0 = c.x, c1 = c.y, c2 = c.z, c3 = c.w, k0 = k.x, k1 = k.y;
    for (int r = 0; r < rounds; r++) {
        if (r > 0) k0 += PHILOX_W0, k1 += PHILOX_W1;
        ulong p0 = (ulong)PHILOX_M0 * c0, p1 = (ulong)PHILOX_M1 * c2;
        uint n0 = (uint)(p1 >> 32) ^ c1 ^ k0, n2 = (uint)(p0 >> 32) ^ c3 ^ k1;
        c1 = (uint)p1, c3 = (uint)p0, c0 = n0, c2 = n2;
    }
    return (uint4)(c0, c1, c2, c3);
}

LSQT_INLINE uint4 philox4x32_10(uint4 c, uint2 k) { return philox4x32_rounds(c, k, 10); }

/* The stream of one path: key = seed, counter = (draw block, path index low, path index
 * high 16 bits | purpose << 16, slice). A path is therefore a pure function of
 * (seed, slice, path index, purpose). */
#define RNG_PURPOSE_WALK 0u
#define RNG_PURPOSE_CANDIDATES 1u /* RRSS: the analog walks whose exits are candidate directions */
/* LSQT_RNG_BELOW (device_layout.h) is OR'ed into either for the slices from below. */

/* The counter of a path's first block (docs/design.md section 4.1). */
LSQT_INLINE uint4 rng_counter(uint slice, ulong path, uint purpose)
{
    return (uint4)(0u, (uint)path, ((uint)(path >> 32) & 0xFFFFu) | (purpose << 16), slice);
}

#ifdef LSQT_RNG_WIDE
/* A CPU's form (the host passes -DLSQT_RNG_WIDE=1): four blocks at once, counters
 * ctr.x ... ctr.x + 3, as four 4-lane vectors (one lane per block), so each round's
 * multiplies are two vector multiplies for four blocks; out[4 b + j] is word j of block b,
 * the order of the one-block form's draws. On a GPU a work-item's vectors are sequential
 * work and its 32-word buffers would be registers, so it keeps the one-block form. */
/* Philox's ten rounds on N blocks at once, word j of block b in lane b of cj (N 4 or 8). */
#define PHILOX_ROUNDS_N(N, c0, c1, c2, c3, key)                                                                       \
    do {                                                                                                              \
        uint k0_ = (key).x, k1_ = (key).y;                                                                            \
        for (int r_ = 0; r_ < 10; r_++) {                                                                             \
            ulong##N p0_ = (ulong##N)(PHILOX_M0) * convert_ulong##N(c0), p1_ = (ulong##N)(PHILOX_M1) * convert_ulong##N(c2); \
            uint##N n0_ = convert_uint##N(p1_ >> 32) ^ c1 ^ (uint##N)(k0_);                                           \
            uint##N n2_ = convert_uint##N(p0_ >> 32) ^ c3 ^ (uint##N)(k1_);                                           \
            c1 = convert_uint##N(p1_), c3 = convert_uint##N(p0_), c0 = n0_, c2 = n2_;                                 \
            k0_ += PHILOX_W0, k1_ += PHILOX_W1; /* the key of the next round */                                       \
        }                                                                                                             \
    } while (0)

LSQT_INLINE void philox4x32_10_x4(uint4 ctr, uint2 key, uint *out)
{
    uint4 c0 = (uint4)(ctr.x) + (uint4)(0u, 1u, 2u, 3u), c1 = (uint4)(ctr.y), c2 = (uint4)(ctr.z), c3 = (uint4)(ctr.w);
    PHILOX_ROUNDS_N(4, c0, c1, c2, c3, key);
    vstore4((uint4)(c0.x, c1.x, c2.x, c3.x), 0, out);
    vstore4((uint4)(c0.y, c1.y, c2.y, c3.y), 1, out);
    vstore4((uint4)(c0.z, c1.z, c2.z, c3.z), 2, out);
    vstore4((uint4)(c0.w, c1.w, c2.w, c3.w), 3, out);
}

/* The same for two counters a and b at once (eight lanes, a's blocks first): the rounds
 * are a chain of dependent multiplies, as long for two streams as for one, so two paths'
 * first draws cost what one's did (a path's start was a third of a one-bounce walk). */
LSQT_INLINE void philox4x32_10_x4x2(uint4 a, uint4 b, uint2 key, uint *out_a, uint *out_b)
{
    const uint4 step = (uint4)(0u, 1u, 2u, 3u);
    uint8 c0 = (uint8)((uint4)(a.x) + step, (uint4)(b.x) + step), c1 = (uint8)((uint4)(a.y), (uint4)(b.y));
    uint8 c2 = (uint8)((uint4)(a.z), (uint4)(b.z)), c3 = (uint8)((uint4)(a.w), (uint4)(b.w));
    PHILOX_ROUNDS_N(8, c0, c1, c2, c3, key);
    vstore4((uint4)(c0.s0, c1.s0, c2.s0, c3.s0), 0, out_a);
    vstore4((uint4)(c0.s1, c1.s1, c2.s1, c3.s1), 1, out_a);
    vstore4((uint4)(c0.s2, c1.s2, c2.s2, c3.s2), 2, out_a);
    vstore4((uint4)(c0.s3, c1.s3, c2.s3, c3.s3), 3, out_a);
    vstore4((uint4)(c0.s4, c1.s4, c2.s4, c3.s4), 0, out_b);
    vstore4((uint4)(c0.s5, c1.s5, c2.s5, c3.s5), 1, out_b);
    vstore4((uint4)(c0.s6, c1.s6, c2.s6, c3.s6), 2, out_b);
    vstore4((uint4)(c0.s7, c1.s7, c2.s7, c3.s7), 3, out_b);
}

typedef struct {
    uint4 ctr;     /* the counter of the first block not yet made */
    uint2 key;
    uint buf[16];  /* the four blocks being drawn from */
    uint next[16]; /* the four after them, made ahead once the path has used its first four */
    int used, ahead;
} rng_t;

LSQT_INLINE rng_t rng_init(uint seed_lo, uint seed_hi, uint slice, ulong path, uint purpose)
{
    rng_t r;
    r.key = (uint2)(seed_lo, seed_hi);
    r.ctr = rng_counter(slice, path, purpose);
    philox4x32_10_x4(r.ctr, r.key, r.buf);
    r.ctr.x += 4u;
    r.used = 0, r.ahead = 0;
    return r;
}

/* rng_init of paths pa (into *a) and pb (into *b), the same streams, made together. */
LSQT_INLINE void rng_init_pair(uint seed_lo, uint seed_hi, uint slice, ulong pa, ulong pb, uint purpose, rng_t *a,
                               rng_t *b)
{
    a->key = b->key = (uint2)(seed_lo, seed_hi);
    a->ctr = rng_counter(slice, pa, purpose), b->ctr = rng_counter(slice, pb, purpose);
    philox4x32_10_x4x2(a->ctr, b->ctr, a->key, a->buf, b->buf);
    a->ctr.x += 4u, b->ctr.x += 4u;
    a->used = b->used = 0, a->ahead = b->ahead = 0;
}

/* Most paths of a thin slab use fewer than 16 draws, so the first four blocks come
 * alone; a longer path then makes each next four when it starts on the current ones, so
 * their rounds overlap its scattering events instead of heading one's chain. */
__attribute__((noinline)) void rng_refill(rng_t *r)
{
    if (r->ahead)
        for (int i = 0; i < 16; i++) r->buf[i] = r->next[i];
    else
        philox4x32_10_x4(r->ctr, r->key, r->buf), r->ctr.x += 4u;
    philox4x32_10_x4(r->ctr, r->key, r->next);
    r->ctr.x += 4u;
    r->used = 0, r->ahead = 1;
}

__attribute__((always_inline)) inline uint rng_next_u32(rng_t *r)
{
    if (r->used == 16) rng_refill(r);
    return r->buf[r->used++];
}
#else
typedef struct {
    uint4 ctr; /* the counter of the next block */
    uint2 key;
    uint4 buf; /* the block being drawn from */
    int used;
} rng_t;

LSQT_INLINE rng_t rng_init(uint seed_lo, uint seed_hi, uint slice, ulong path, uint purpose)
{
    rng_t r;
    r.key = (uint2)(seed_lo, seed_hi);
    r.ctr = rng_counter(slice, path, purpose);
    r.buf = (uint4)(0u);
    r.used = 4;
    return r;
}

/* The draws come block after block, each made when it is first needed (the GPU path: a
 * block made ahead, to overlap its rounds with other work, kept five more VGPRs live
 * through the walk on gfx90a, and a GPU hides that latency with more waves instead). */
LSQT_INLINE uint rng_next_u32(rng_t *r)
{
    if (r->used == 4) {
        r->buf = philox4x32_10(r->ctr, r->key);
        r->ctr.x++;
        r->used = 0;
    }
    uint v = r->used == 0 ? r->buf.x : r->used == 1 ? r->buf.y : r->used == 2 ? r->buf.z : r->buf.w;
    r->used++;
    return v;
}
#endif

/* Uniform in [0, 1). */
LSQT_INLINE real rng_uniform(rng_t *r)
{
#ifdef LSQT_DOUBLE
    ulong a = rng_next_u32(r) >> 5, b = rng_next_u32(r) >> 6; /* 27 + 26 = 53 bits */
    return (real)(a * 67108864ul + b) * 0x1.0p-53;
#else
    return (real)(rng_next_u32(r) >> 8) * 0x1.0p-24f;
#endif
}
