/* The parsed, validated and pruned layered assembly (docs/design.md section 1): plain C structs that the
 * parser fills and every later stage (device tables, LSS, reports) reads. */
#ifndef LSQT_ASSEMBLY_H
#define LSQT_ASSEMBLY_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#include "lsqt/model_list.h"

#define LSQT_MAX_MODEL_KEYS 6 /* most keys a model has (a static check in host/input/lsqt.c) */

typedef struct lsqt_phase {
    int kind;                  /* enum lsqt_phase_kind */
    double v[LSQT_MAX_MODEL_KEYS]; /* its keys' values, slot LSQT_<ID>_<key> (model_list.h) */
    int table;                 /* its TABLE key's table: 1 + its index in the assembly's
                                  phase_tables, 0 for none (also in v[], its key's slot) */
} lsqt_phase;

/* A phase function's table (a model's TABLE key, model_list.h): n >= 2 rows of cos theta
 * (mu, increasing from -1 to 1), its value p normalised to 2 pi int p dmu = 1 (the
 * trapezoid rule: exact for the linear interpolation the kernels evaluate), and cdf, the
 * integral from -1 to mu[i] (0 at mu[0], 1 at mu[n-1]). hash: FNV-1a of the rows (mu, p)
 * normalised, what the canonical text says of the table (a table and its multiples are
 * the same phase function). */
typedef struct lsqt_phase_table {
    int n;
    double *mu, *p, *cdf;
    uint64_t hash;
    char *path; /* the file as opened, so that no output of the run lands on it (or NULL) */
} lsqt_phase_table;

/* Reads TEXT (rows "cos_theta value", '#' comments, either order in cos theta) into *t.
 * Returns 0, or 2 with "NAME:LINE: why" in err. lsqt_phase_table_free frees it. */
int lsqt_phase_table_parse(const char *text, size_t len, const char *name, lsqt_phase_table *t, char *err,
                           size_t errcap);
void lsqt_phase_table_free(lsqt_phase_table *t);

typedef struct lsqt_medium {
    double eta, mua, mus;
    lsqt_phase phase;  /* kind NONE when mus == 0 */
    int line;          /* 1-based source line */
} lsqt_medium;

typedef struct lsqt_layer {
    double z;
    int kind;          /* enum lsqt_bsdf_kind */
    double v[LSQT_MAX_MODEL_KEYS]; /* its BSDF's keys, slot LSQT_<ID>_<key> (model_list.h) */
    int iter_count;    /* a microsurface's walks per vertex, resolved (auto applied); else 0 */
    int multiple_scattering; /* a microsurface's use_multiple_scattering (0/1); else 0 */
    int line;
} lsqt_layer;

typedef struct lsqt_assembly {
    int n_layers;          /* after pruning, >= 1 */
    lsqt_layer *layers;    /* n_layers, top to bottom */
    lsqt_medium *media;    /* n_layers + 1, top to bottom */
    int n_pruned_layers;   /* layers removed as unreachable */
    /* A run with bands (docs/guide.md, "Colour and spectra"): n_bands > 1, and band[b] is
     * band b's one-band assembly (band[0]'s values are the ones above). Every band has the
     * same layers, models and geometry; only the numbers differ. One band: 0 and NULL. */
    int n_bands;
    struct lsqt_assembly *band;
    double *wavelengths;   /* n_bands nm, or NULL: unnamed bands (three are R, G, B) */
    int n_tables;          /* the @FILE tables the text read (paths as opened), so that no */
    char **tables;         /* output of the run lands on one */
    int n_phase_tables;    /* the phase functions' tables (lsqt_phase.table), the same */
    lsqt_phase_table *phase_tables; /* in every band: each band's assembly holds its own copy */
} lsqt_assembly;

/* Diagnostics. The parser never prints: it fills this, the caller decides. */
#define LSQT_DIAG_MAX_NOTES 32
typedef struct lsqt_diag {
    char error[1024];      /* "LINE:COL? ..." empty when no error */
    int error_line;        /* 0 when no error or not line-specific */
    int n_notes;
    char notes[LSQT_DIAG_MAX_NOTES][256];
} lsqt_diag;

/* Parses and validates LSQT text (need not be NUL terminated). `name` is used in messages
 * ("file.lsqt:3: ..."). Every rule of the LSQT language (docs/guide.md) applies, pruning
 * included (with notes). The bands: wavelengths wl (n_wl of them, nm, increasing) or, wl
 * NULL, n_wl 1 for one band (a comma list is refused) or 0 (the first comma list sets the
 * band count); relative @FILE tables read from dir. One band gives a one-band assembly;
 * more give every band's assembly (n_bands, band[]), each parsed and checked with
 * lsqt_parse_band, pruned where every band is stopped (notes are band 1's). Returns 0, or
 * 2 with diag->error filled and *out left empty. */
int lsqt_parse(const char *text, size_t len, const char *name, const double *wl, int n_wl, const char *dir,
               lsqt_assembly *out, lsqt_diag *diag);

/* lsqt_parse of band `band` alone, for a run with bands (lsqt/bands.h): a number key may then be a
 * comma list (one value per band) or @FILE (a table, interpolated at the band's
 * wavelength), and this takes band `band`'s value; every rule holds per band, and an error
 * names the band. bands NULL is one band, where a list is refused. */
struct lsqt_bands;
int lsqt_parse_band(const char *text, size_t len, const char *name, struct lsqt_bands *bands, int band,
                    lsqt_assembly *out, lsqt_diag *diag);

/* Joins n one-band assemblies of the same stack (moved into out->band; not freed) and a
 * copy of wl (NULL: unnamed) into one with bands. Returns 0, or 2 out of memory (each
 * untouched). */
int lsqt_assembly_join(lsqt_assembly *each, int n, const double *wl, lsqt_assembly *out);

/* The number of bands (1 for a one-band assembly), and band b's assembly (A itself then). */
int lsqt_assembly_bands(const lsqt_assembly *a);
const lsqt_assembly *lsqt_assembly_band(const lsqt_assembly *a, int b);

void lsqt_assembly_free(lsqt_assembly *a);

/* A copy of FROM's phase tables into TO (which has none): an assembly made from another's
 * media (a mirror image) must carry them. Returns 0, or 2 out of memory (TO's freed with
 * TO). */
int lsqt_phase_tables_copy(const lsqt_assembly *from, lsqt_assembly *to);

/* Canonical text of the assembly: one line per medium/layer, seed model names, every
 * key written with %.17g, so that equal assemblies give equal text. With bands, a first
 * line "# bands N: W1,W2,... nm" (or "# bands N") and a comma list wherever the bands'
 * values differ, which lsqt_parse reads back. Returns the length
 * it needs (excluding NUL); writes at most cap bytes including the NUL. */
size_t lsqt_assembly_canonical(const lsqt_assembly *a, char *buf, size_t cap);

/* 64-bit FNV-1a of the canonical text. */
uint64_t lsqt_assembly_hash(const lsqt_assembly *a);

/* OpenCL build options that enable only the models used: "-DLSQT_HAS_PHASE_HG=1 ...".
 * Returns the length needed, like lsqt_assembly_canonical. */
size_t lsqt_assembly_build_options(const lsqt_assembly *a, char *buf, size_t cap);

/* 1 when light can reach the bottom medium (some transmission possible) in some band. */
int lsqt_assembly_transmits(const lsqt_assembly *a);

/* 1 unless the layer transmits nothing (Lambertian or microsurface Lambertian with
 * fT = 0, microsurface dielectric with kT = 0, Oren-Nayar, conductive): light never
 * passes it, so what lies below is pruned. */
int lsqt_layer_transmits(const lsqt_layer *l);

/* Seed names of the models, for messages. */
const char *lsqt_bsdf_name(int kind);
const char *lsqt_phase_name(int kind);

#ifdef __cplusplus
}
#endif
#endif
