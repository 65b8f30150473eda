/* Philox4x32 (Salmon, Moraes, Dror, Shaw 2011): a counter-based generator; 10 rounds for
 * simulation. The round count is a parameter only so the harness can check the published
 * 7-round known answers too. */
#define PHILOX_M0 0xD2511F53u
#define PHILOX_M1 0xCD9E8D57u
#define PHILOX_W0 0x9E3779B9u
#define PHILOX_W1 0xBB67AE85u

/* Both halves of each 32x32 product from one 64-bit multiply: PoCL's mul_hi builds it from
 * 16-bit pieces (it was most of the cost of a scattering event), and a GPU compiles this
 * form to its native high multiply too. */
inline uint4 philox4x32_round(uint4 c, uint2 k)
{
    ulong p0 = (ulong)PHILOX_M0 * c.x, p1 = (ulong)PHILOX_M1 * c.z;
    uint hi0 = (uint)(p0 >> 32), lo0 = (uint)p0;
    uint hi1 = (uint)(p1 >> 32), lo1 = (uint)p1;
    return (uint4)(hi1 ^ c.y ^ k.x, lo1, hi0 ^ c.w ^ k.y, lo0);
}

inline uint4 philox4x32_rounds(uint4 c, uint2 k, int rounds)
{
    for (int r = 0; r < rounds; r++) {
        if (r > 0) k += (uint2)(PHILOX_W0, PHILOX_W1);
        c = philox4x32_round(c, k);
    }
    return c;
}

inline uint4 philox4x32_10(uint4 c, uint2 k) { return philox4x32_rounds(c, k, 10); }

/* The stream of one path: key = seed, counter = (draw block, path index low, path index
 * high 16 bits | purpose << 16, slice). A path is therefore a pure function of
 * (seed, slice, path index, purpose). */
typedef struct {
    uint4 ctr;
    uint2 key;
    uint4 buf;
    int used;
} rng_t;

#define RNG_PURPOSE_WALK 0u
#define RNG_PURPOSE_CANDIDATES 1u /* RRSS: the analog walks whose exits are candidate directions */
/* LSQT_RNG_BELOW (device_layout.h) is OR'ed into either for the slices from below. */

inline rng_t rng_init(uint seed_lo, uint seed_hi, uint slice, ulong path, uint purpose)
{
    rng_t r;
    r.key = (uint2)(seed_lo, seed_hi);
    r.ctr = (uint4)(0u, (uint)path, ((uint)(path >> 32) & 0xFFFFu) | (purpose << 16), slice);
    r.buf = (uint4)(0u);
    r.used = 4;
    return r;
}

inline uint rng_next_u32(rng_t *r)
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

/* Uniform in [0, 1). */
inline real rng_uniform(rng_t *r)
{
#ifdef LSQT_DOUBLE
    ulong a = rng_next_u32(r) >> 5, b = rng_next_u32(r) >> 6; /* 27 + 26 = 53 bits */
    return (real)(a * 67108864ul + b) * 0x1.0p-53;
#else
    return (real)(rng_next_u32(r) >> 8) * 0x1.0p-24f;
#endif
}
