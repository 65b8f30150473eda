#include "lsqt/state.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

size_t lsqt_state_nee_count(const lsqt_state *st)
{
    return (size_t)st->n_slices * LSQT_BATCHES * (size_t)st->n_wi;
}

size_t lsqt_state_scalar_count(const lsqt_state *st)
{
    return (size_t)st->n_slices * LSQT_BATCHES * LSQT_T_COUNT;
}

size_t lsqt_state_hist_count(const lsqt_state *st)
{
    return (size_t)st->n_slices * LSQT_BATCHES * LSQT_HIST_BINS;
}

int lsqt_state_init(lsqt_state *st, const char *canonical, uint64_t hash, uint64_t seed,
                    int n_slices, int n_wi, int transmits)
{
    memset(st, 0, sizeof *st);
    st->hash = hash;
    st->seed = seed;
    st->n_slices = n_slices;
    st->n_wi = n_wi;
    st->transmits = transmits;
    st->canonical = malloc(strlen(canonical) + 1);
    st->theta_o = calloc((size_t)n_slices, sizeof *st->theta_o);
    st->wi = calloc((size_t)n_slices * (size_t)n_wi * 4, sizeof *st->wi);
    st->nee = calloc(lsqt_state_nee_count(st), sizeof *st->nee);
    st->scalars = calloc(lsqt_state_scalar_count(st), sizeof *st->scalars);
    st->hist = calloc(lsqt_state_hist_count(st), sizeof *st->hist);
    if (!st->canonical || !st->theta_o || !st->wi || !st->nee || !st->scalars || !st->hist) {
        lsqt_state_free(st);
        return -1;
    }
    strcpy(st->canonical, canonical);
    return 0;
}

void lsqt_state_free(lsqt_state *st)
{
    free(st->canonical);
    free(st->theta_o);
    free(st->wi);
    free(st->nee);
    free(st->scalars);
    free(st->hist);
    memset(st, 0, sizeof *st);
}

uint64_t lsqt_batch_paths(uint64_t total, int b)
{
    uint64_t full = total / LSQT_CHUNK, rest = total % LSQT_CHUNK;
    uint64_t chunks = full / LSQT_BATCHES + ((uint64_t)b < full % LSQT_BATCHES ? 1u : 0u);
    return chunks * LSQT_CHUNK + (full % LSQT_BATCHES == (uint64_t)b ? rest : 0u);
}

double lsqt_u128_to_double(lsqt_u128 v) { return ldexp((double)v.hi, 64) + (double)v.lo; }

lsqt_u128 lsqt_u128_add(lsqt_u128 a, lsqt_u128 b)
{
    lsqt_u128 r = {a.lo + b.lo, a.hi + b.hi};
    r.hi += r.lo < a.lo;
    return r;
}
