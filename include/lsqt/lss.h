/* LSS: the progressive state file (docs/design.md section 6.1; the bytes: docs/formats.md). Versioned little-endian binary:
 *   "LSQTLSS\0", u32 version, u32 chunk, batches, fix_bits, hist_nmu, hist_nphi, t_count,
 *   u64 seed, u64 assembly hash, u32 double, transmits, flags, u32 direction method
 *   (0 spread, 1 RRSS, 2 file, 3 grid), u32 RRSS rx, u64 RRSS pilot paths,
 *   u32 n_slices, n_wi, u64 paths, u64 span end, u32 stage (0 run, 1 RRSS pilot shard),
 *   u32 range count, u32 text length, u64 file size in bytes, u32 grid NI, u32 grid NPHI
 *   (direction method 3, --grid; else 0), [version 7: u32 bands (2 to 4096), u32 named
 *   (1: their wavelengths follow the text)], canonical assembly text, [named: bands x f64 nm],
 *   range count x (u64 lo, u64 hi): the path indices held, sorted and disjoint,
 *   per slice: f64 theta_o, u32 slice flags (1: light from below), u64 paths, n_wi x f32 (x, y, z),
 *              then its tallies, band after band (version 7), [batch][n_wi] point-estimate sums, [batch][t_count] scalars,
 *              [batch][hist_bins] histogram, each a u128 of 2^-fix_bits units, packed: a
 *              sequence of LEB128 varint tokens t, t = 2k a run of k zero tallies, t = 2L + 1
 *              a tally in the next L bytes (1..16, little-endian, the last nonzero),
 *   u32 CRC-32 of everything before it.
 * Version 5 (read, never written) had no file size and every tally in 16 bytes (two u64,
 * low first). Nothing that depends on timing is stored, so equal work gives
 * byte-identical files. */
#ifndef LSQT_LSS_H
#define LSQT_LSS_H

#include <stddef.h>

#include "lsqt/state.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LSQT_LSS_VERSION 7u /* 7: bands (written only with more than one; one band is still 6); 6: packed tallies, file size; 5: path ranges, span, stage, slice flags; 4: direction method, RRSS rx and pilot paths; 3: work counters, histogram per
                             batch; 2: 128-bit tallies of 2^-40 (1: 64-bit of 2^-30) */

/* Written through lsqt_out (util.h: atomic for regular files). Returns 0 or -1. */
int lsqt_lss_write(const char *path, const lsqt_state *st, char *err, size_t errcap);

/* Reads and checks everything (magic, version, sizes, CRC, layout constants). Returns 0,
 * or -1 with err saying what is wrong, checked in this order: "empty file", "not an LSS
 * file (bad magic)", "LSS version N, this lsqt-cl reads versions 5 to 7", "truncated at byte
 * N (...)", "corrupt LSS file (CRC mismatch ...)", then what a valid CRC cannot vouch for
 * (another tally layout, an impossible header); lsqt_lss_read puts the path in front.
 * Never accepts a truncated or corrupt file. */
int lsqt_lss_read(const char *path, lsqt_state *st, char *err, size_t errcap);
int lsqt_lss_parse(const unsigned char *data, size_t len, lsqt_state *st, char *err, size_t errcap);

#ifdef __cplusplus
}
#endif
#endif
