/* The GPU code path's next-event records (-DLSQT_NEE_RECORDS; the layout, lsqt_nee_rec,
 * is device_layout.h's). The walk makes no estimates there: at each next-event vertex it
 * writes the vertex's state that does not depend on the incident direction as a record,
 * in the path's order, and lsqt_estimate evaluates the records towards every direction,
 * a work-group sharing the directions (walk.cl). The CPU code path sums the terms at the
 * vertex and writes no record. These types are part of walk_ctx and ms_sink on both paths;
 * only the GPU path calls nee_write and nee_ms_vtx. */

/* A record's kind (LSQT_NEE_KIND); its fields are read as nee_rec_vec (walk.cl) says. */
#define NEE_LAYER 0     /* a layer's BSDF: v = wo */
#define NEE_MEDIUM 1    /* a medium's phase: v = wo, m, the optical depths in lam_v, lg_v */
#define NEE_MS_VERTEX 2 /* a microsurface walk's vertex (ms_vtx) */
#define NEE_MS_FIRST 3  /* a microsurface's first record: its closed-form single scattering
                         * (SINGLE_WALK) or its walk's first vertex (WALK) */
#define NEE_SPREAD 4    /* a band block's: the factors that spread the vertex's terms, at
                         * weight 1 in the records before it, to each band (bands.cl) */

/* The records of one spread: LSQT_NEE_SPREAD_BANDS bands each. */
#define NEE_SPREAD_RECORDS ((LSQT_NB + LSQT_NEE_SPREAD_BANDS - 1) / LSQT_NEE_SPREAD_BANDS)

/* A work counter (walk.cl's LSQT_T_LAYER_EVENTS ...): on the CPU path the work-item's,
 * 64-bit; on the GPU path its one path's, 32-bit (a path has at most LSQT_MAX_EVENTS
 * events, and no more next-event vertices than records, which nee_out counts in 32 bits):
 * three 64-bit counters live through the walk cost some 20 VGPRs on gfx90a. */
#ifdef LSQT_NEE_RECORDS
typedef uint work_t;
#define LSQT_RECORDS 1 /* the code path, for a C test where both paths compile */
#else
typedef ulong work_t;
#define LSQT_RECORDS 0
#endif

/* Where a path's records go: rec[n ...], the launch's buffer (the same for every
 * work-item: no per-path pointer held through the walk) from the path's first record on;
 * rec 0: only counted, from n = 0. The host keeps a launch's records below 2^31
 * (session.c record_budget). */
typedef struct {
    __global lsqt_nee_rec *rec;
    uint n;
} nee_out;

/* The record of a vertex: kind, the layer's or medium's index, weight w, side (a
 * microsurface's, else 0) and the fields of x; written to the path's next place, or
 * only counted. */
LSQT_INLINE void nee_write(nee_out *out, int kind, int index, real w, real side, const ms_vtx *x)
{
    if (out->rec) {
        __global lsqt_nee_rec *r = out->rec + out->n;
        LSQT_NEE_V(*r) = x->v, LSQT_NEE_INV_AREA(*r) = x->inv_area;
        LSQT_NEE_M(*r) = x->m, LSQT_NEE_LAM_V(*r) = x->lam_v, LSQT_NEE_LG_V(*r) = x->lg_v;
        LSQT_NEE_LOG_C(*r) = x->log_c, LSQT_NEE_LOG_CBAR(*r) = x->log_cbar, LSQT_NEE_E(*r) = x->e;
        LSQT_NEE_W(*r) = w, LSQT_NEE_SIDE(*r) = side;
        LSQT_NEE_KIND(*r) = (real)kind, LSQT_NEE_INDEX(*r) = (real)index;
    }
    out->n++;
}

/* A microsurface record's vertex, as nee_write took it (its kind, index, weight and side
 * are LSQT_NEE_KIND ...; a layer's or a medium's record is read field by field,
 * nee_rec_vec). */
LSQT_INLINE ms_vtx nee_ms_vtx(const lsqt_nee_rec *r)
{
    ms_vtx x;
    x.v = LSQT_NEE_V(*r), x.inv_area = LSQT_NEE_INV_AREA(*r);
    x.m = LSQT_NEE_M(*r), x.lam_v = LSQT_NEE_LAM_V(*r), x.lg_v = LSQT_NEE_LG_V(*r);
    x.log_c = LSQT_NEE_LOG_C(*r), x.log_cbar = LSQT_NEE_LOG_CBAR(*r), x.e = LSQT_NEE_E(*r);
    return x;
}
