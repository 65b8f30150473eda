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
inline uint4 philox4x32_rounds(uint4 c, uint2 k, int rounds)
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

inline uint4 philox4x32_10(uint4 c, uint2 k) { return philox4x32_rounds(c, k, 10); }

/* The stream of one path: key = seed, counter = (draw block, path index low, path index
 * high 16 bits | purpose << 16, slice). A path is therefore a pure function of
 * (seed, slice, path index, purpose). */
typedef struct {
    uint4 ctr;  /* the counter of the block after `next` */
    uint2 key;
    uint4 buf;  /* the block being drawn from */
    uint4 next; /* the block after it, made ahead */
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
    r.next = philox4x32_10(r.ctr, r.key);
    r.ctr.x++;
    r.used = 4;
    return r;
}

/* The draws come block after block as before; the block after the current one is made
 * when the current one starts, not when it is first needed: nothing waits on it then,
 * so its 10 rounds of multiplies overlap the scattering event that uses the current
 * block, instead of heading its chain of dependent work (a path makes one block more
 * than it uses). */
inline uint rng_next_u32(rng_t *r)
{
    if (r->used == 4) {
        r->buf = r->next;
        r->next = philox4x32_10(r->ctr, r->key);
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
