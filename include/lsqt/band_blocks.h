/* Band blocks: which bands of a run share their paths, and the tables of a block
 * (kernels/bands.cl; docs/architecture.md, "Bands"). */
#ifndef LSQT_BAND_BLOCKS_H
#define LSQT_BAND_BLOCKS_H

#include "lsqt/assembly.h"
#include "lsqt/device_layout.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The widest block a program is built for (the kernels' per-band arrays are this long at
 * most); the default width, and LSQT_BAND_BLOCK=1 ... 16 to choose another (1: every band
 * walks its own paths, as a one-band run). */
#define LSQT_BAND_BLOCK_MAX 16

/* The widest block on the GPU code path: its walk keeps a block's state in the group's
 * local memory and lsqt_estimate a path's band sums in registers, which at 4 bands stay
 * within 128 VGPRs and 16 KB of local memory a SIMD on gfx90a (4 waves of 64;
 * tests/test_gpu_build.py builds every width up to it). */
#define LSQT_GPU_BAND_BLOCK_MAX 4

/* What sharing pays (docs/design.md 3.7): two bands whose paths diverge by D
 * (host/sim/band_blocks.c path_divergence) see about e^-D of each other's paths as their
 * own, so in a block of k bands whose paths pairwise diverge by at most D a band has at
 * least 1 + (k - 1) e^-D paths' worth of its own for about 1 + LSQT_BAND_COST (k - 1)
 * one-band runs' work (a band's own next-event terms and tallies). Bands share where that
 * predicted efficiency gain is at least LSQT_BAND_GAIN_MIN for every band, a margin for
 * what the model leaves out (fitted on the Mie paint and dusty coats of
 * docs/performance.md: at D = 1 two bands' errors grow 1.2 times, at D = 2.3 to 3.8 1.3 to
 * 1.9 times). */
#define LSQT_BAND_COST 0.4
#define LSQT_BAND_GAIN_MIN 1.3

/* A block: its width nb (the program's LSQT_NB) and the run's band in each of its slots,
 * -1 for a slot that only pads the block (it repeats the block's last band; its tallies are dropped). */
typedef struct lsqt_band_block {
    int nb;
    int band[LSQT_BAND_BLOCK_MAX];
} lsqt_band_block;

/* Whether bands b and c of A can share their paths: the same stack and models, and
 * values that differ only where a block has a factor per band (a closed layer's fR and
 * fT; an interior medium's mus and mua, hence mut; a hidden conductor's n and k, one
 * under another non-null layer; a phase function's parameters where its sampler is
 * exact: the block samples the hero's and weighs each band by its own, kernels/bands.cl;
 * another phase function only where one band has no scattering). */
int lsqt_bands_share(const lsqt_assembly *a, int b, int c);

/* The divergence of the paths of bands b and c (host/sim/band_blocks.c path_divergence;
 * INFINITY where they cannot share). */
double lsqt_bands_divergence(const lsqt_assembly *a, int b, int c);

/* The largest divergence of two bands' paths in a block of k bands that the model
 * allows (LSQT_BAND_GAIN_MIN); INFINITY for k = 1. */
double lsqt_band_divergence_allowed(int k);

/* Parts A's bands into blocks of at most width bands that share their paths and whose
 * paths differ by at most max_divergence (< 0: lsqt_band_divergence_allowed of the
 * group's size; INFINITY: every band that can share does) (in
 * LSQT_BAND_BLOCK_MAX or fewer slots, the blocks of a group evenly filled); returns the
 * count, or -1 when out of memory; *out is malloc'ed. */
int lsqt_band_blocks(const lsqt_assembly *a, int width, double max_divergence, lsqt_band_block **out);

/* The divergence asked for (LSQT_BAND_DIVERGENCE, a number >= 0 or inf), -1 for the
 * model's (unset), -2 with err set for a bad value. */
double lsqt_band_divergence_max(char *err, size_t errcap);

/* The width asked for (LSQT_BAND_BLOCK, else LSQT_BAND_BLOCK_MAX); 0 with err set for a
 * bad value. */
int lsqt_band_block_width(char *err, size_t errcap);

/* A block's device tables: its layers' unit models, its media with the least extinction
 * and depths of its bands (and a phase function from a band that scatters), and bw (of
 * LSQT_BAND_TAB_SIZE(n_layers, nbp) reals, zeroed by the caller; nbp: the band count
 * padded to the kernels' vector width) each medium's largest extinction and the
 * per-band factors. Extinctions within same_mut (relative) of a medium's least are taken
 * as the least (the float kernels: 2^-19, what 6-digit decimals miss by; 0 in double).
 * band_media: each slot's own media (blk->nb x (n_layers + 1): its phase function,
 * extinction and depths; where a band does not scatter, the reference's phase function).
 * Returns 0, or 1 when out of memory. */
int lsqt_band_block_tables(const lsqt_assembly *a, const lsqt_band_block *blk, int nbp, double same_mut,
                           lsqt_dev_scene *scene, lsqt_dev_medium_d *media, lsqt_dev_layer_d *layers, double *bw,
                           lsqt_dev_medium_d *band_media);

#ifdef __cplusplus
}
#endif
#endif
