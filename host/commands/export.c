/* lsqt-cl export: the BSDF of a grid LSS (--grid) as a NetCDF file that xarray opens as
 * labelled arrays and Eradiate's tabulated BSDF reads: the values and their standard
 * errors exactly as `lsqt-cl info --json --bsdf` gives them (the same reduction), laid
 * on the grid's axes, with R, T and delta_T per theta_o and the run's provenance. An LSS
 * that is not on a grid is refused: export writes what was simulated, never a resampling. */
#include "lsqt/export.h"

#include <errno.h>
#include <math.h>
#include <netcdf.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "lsqt/colour.h"
#include "lsqt/directions.h"
#include "lsqt/export_rgl.h"
#include "lsqt/lss.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

#ifndef LSQT_VERSION_STRING
#define LSQT_VERSION_STRING "unknown"
#endif

static void usage(FILE *f, const char *prog)
{
    fprintf(f,
            "usage: %s FILE.lss -o OUT.nc [-q]\n"
            "       %s FILE.lss -o OUT.bsdf --rgl|--rgl-spectral [-q]\n"
            "Writes the BSDF of an LSS made with --grid as NetCDF (netCDF-4): variables brdf\n"
            "and brdf_stderr over (cos_theta_i, phi_d, cos_theta_o), in 1/sr and not\n"
            "cosine-weighted; btdf and btdf_stderr the same when the stack transmits\n"
            "(cos_theta_i is then |cos| of the direction below); R, T, delta_T and their\n"
            "errors over cos_theta_o; _below variables for the slices from below\n"
            "(--from-below); the assembly, seed, paths and versions as attributes. The axes are\n"
            "the grid's: cos theta on linspace(0, 1, N) and phi_d on 2 pi k / NPHI (0: the\n"
            "incident direction on the outgoing one's side), the table Eradiate's mqdiffuse\n"
            "reads. Python: xarray.open_dataset(\"OUT.nc\")[\"brdf\"].\n"
            "A run with bands (--wavelengths, or lists of values) puts a leading dimension\n"
            "channel on every table and on R, T, delta_T: a string coordinate channel (\"550nm\",\n"
            "or R, G, B) and, with wavelengths, a coordinate wavelength (nm) on it:\n"
            "d.brdf.sel(channel=\"550nm\"). One band: no channel dimension.\n"
            "With --rgl, an LSS made with --rgl-grid NT,NU is written as an RGL tensor file\n"
            "(Dupuy and Jakob 2018), the one Mitsuba 3's measured BSDF reads (field rgb: its RGB\n"
            "variants; --rgl-spectral: fields wavelengths and spectra, its spectral variants and\n"
            "pbrt-v4): the reflection from above, f cos(theta) at the grid's nodes, with the\n"
            "standard errors in an extra field `stderr`; transmission and the slices from\n"
            "below are not in it. Colour: one band in every channel (spectra: at 360 and\n"
            "830 nm); bands R, G, B as rgb (not --rgl-spectral); bands with wavelengths as\n"
            "linear sRGB (CIE 1931, D65) or, --rgl-spectral, at the run's wavelengths.\n"
            "\n"
            "  -o, --output OUT      the file (a regular file, written atomically)\n"
            "      --rgl             an RGL tensor file (OUT.bsdf) with an rgb field\n"
            "      --rgl-spectral    an RGL tensor file with wavelengths and spectra fields (the\n"
            "                        run's wavelengths; one band: 360 and 830 nm)\n"
            "  -q, --quiet           print errors only\n"
            "  -h, --help            this text\n"
            "      --version         the version and the commit it was built from\n"
            "Exit status: 0 success, 1 the output could not be written, 2 bad flags or an LSS\n"
            "that cannot be exported (unreadable, not on a grid; bands an RGL file cannot hold).\n",
            prog, prog);
}

/* The NetCDF calls of one file: the first failure is kept (with the call that failed), the
 * rest are skipped, so the writer reads as a list of what the file holds. */
typedef struct ncw {
    int id, status;
    const char *what;
    int sys_errno; /* errno at the first failure: NetCDF says "HDF error" for a full disk */
} ncw;

static void nc_check(ncw *w, int status, const char *what)
{
    if (w->status == NC_NOERR && status != NC_NOERR) w->status = status, w->what = what, w->sys_errno = errno;
}

/* NetCDF's reason for W's failure, with the cause it hides where the system names one (a
 * full disk or quota is "NetCDF: HDF error" otherwise): errno at the failure, or a file
 * system of PATH with no room left. */
static const char *nc_why(const ncw *w, const char *path, char *buf, size_t cap)
{
    char dir[LSQT_PATH_CAP];
    lsqt_path_folder(path, dir, sizeof dir);
    struct statvfs fs;
    const int full = statvfs(dir, &fs) == 0 && (unsigned long long)fs.f_bavail * fs.f_frsize < 65536ULL;
    const int e = w->sys_errno;
    if (e == EDQUOT || e == EFBIG || e == EIO || e == EROFS || e == ENOSPC || (full && w->status != NC_NOERR))
        snprintf(buf, cap, "%s (%s)", strerror(e == EDQUOT || e == EFBIG || e == EIO || e == EROFS ? e : ENOSPC),
                 nc_strerror(w->status));
    else
        snprintf(buf, cap, "%s", nc_strerror(w->status));
    return buf;
}

static void put_text(ncw *w, int var, const char *name, const char *text)
{
    if (w->status == NC_NOERR) nc_check(w, nc_put_att_text(w->id, var, name, strlen(text), text), name);
}

static void put_double_att(ncw *w, int var, const char *name, double v)
{
    if (w->status == NC_NOERR) nc_check(w, nc_put_att_double(w->id, var, name, NC_DOUBLE, 1, &v), name);
}

static int def_var(ncw *w, const char *name, int ndims, const int *dims, const char *units, const char *long_name)
{
    int v = -1;
    if (w->status == NC_NOERR) nc_check(w, nc_def_var(w->id, name, NC_DOUBLE, ndims, dims, &v), name);
    put_text(w, v, "units", units);
    put_text(w, v, "long_name", long_name);
    return v;
}

/* The grid of a state: NO slices per side (the slices of each side in ascending theta_o,
 * slice s at cos node NO-1-s), NI polar nodes, NPHI azimuths, NA of them simulated; NB
 * bands (1: no channel dimension, the file of a one-band run as it always was). */
typedef struct grid {
    int no, ni, nphi, na, below, nb;
    int *side[2]; /* the state's slice index of each side's slice s */
} grid;

/* Direction index of (hemisphere h, cos node ki, azimuth p of NPHI) in a slice's list
 * (directions.h: ((h * NI + i) * NA + m), i = NI-1-ki, m the simulated mirror of p). */
static size_t grid_wi(const grid *g, int h, int ki, int p)
{
    const int m = p <= g->nphi / 2 ? p : g->nphi - p;
    return ((size_t)(h * g->ni + (g->ni - 1 - ki)) * (size_t)g->na + (size_t)m);
}

/* The table of one side and hemisphere: [ki][p][ko] = what(est of slice, direction). */
static void fill_table(const grid *g, const lsqt_slice_est *est, int side, int h, int want_err, double *out)
{
    for (int ki = 0; ki < g->ni; ki++)
        for (int p = 0; p < g->nphi; p++)
            for (int ko = 0; ko < g->no; ko++) {
                const lsqt_est *e = &est[g->side[side][g->no - 1 - ko]].f[grid_wi(g, h, ki, p)];
                out[((size_t)ki * (size_t)g->nphi + (size_t)p) * (size_t)g->no + (size_t)ko] =
                    want_err ? e->err : e->mean;
            }
}

/* The NetCDF ids of one file's dimensions and variables. */
typedef struct nc_vars {
    int d_o, d_p, d_i, d_c; /* dimensions: cos_theta_o, phi_d, cos_theta_i, channel (bands only) */
    int v_ci, v_p, v_co;  /* the axes */
    int v_ch, v_wl;       /* bands: the channel labels, the wavelengths (-1: unnamed bands) */
    int v_f[2][2][2];     /* per side (from above; from below), hemisphere (R; T), value or error */
    int v_s[2][6];        /* per side: R, T, delta_T and their errors */
} nc_vars;

static const char *const scal[6] = {"R", "R_stderr", "T", "T_stderr", "delta_T", "delta_T_stderr"};

/* The dimensions and the axes' variables. With bands, `channel` comes first (the slowest
 * axis: each band's table is contiguous, as in the LSS), labelled by a string coordinate
 * ("550nm", "R"), with the wavelengths beside it when the run has them. */
static void define_axes(ncw *w, const lsqt_state *st, const grid *g, nc_vars *v)
{
    v->d_o = -1, v->d_p = -1, v->d_i = -1, v->d_c = -1, v->v_ch = -1, v->v_wl = -1;
    if (g->nb > 1) {
        nc_check(w, nc_def_dim(w->id, "channel", (size_t)g->nb, &v->d_c), "channel");
        if (w->status == NC_NOERR) nc_check(w, nc_def_var(w->id, "channel", NC_STRING, 1, &v->d_c, &v->v_ch), "channel");
        put_text(w, v->v_ch, "long_name", st->wavelengths ? "band (its wavelength)" : "band (R, G, B: colour channels)");
        if (st->wavelengths) {
            v->v_wl = def_var(w, "wavelength", 1, &v->d_c, "nm", "wavelength of the band");
            put_text(w, v->v_wl, "standard_name", "radiation_wavelength");
        }
    } else if (st->wavelengths) { /* one band with its wavelength: a scalar coordinate */
        v->v_wl = def_var(w, "wavelength", 0, NULL, "nm", "wavelength of the band");
        put_text(w, v->v_wl, "standard_name", "radiation_wavelength");
    }
    if (w->status == NC_NOERR) nc_check(w, nc_def_dim(w->id, "cos_theta_i", (size_t)g->ni, &v->d_i), "cos_theta_i");
    if (w->status == NC_NOERR) nc_check(w, nc_def_dim(w->id, "phi_d", (size_t)g->nphi, &v->d_p), "phi_d");
    if (w->status == NC_NOERR) nc_check(w, nc_def_dim(w->id, "cos_theta_o", (size_t)g->no, &v->d_o), "cos_theta_o");
    v->v_ci = def_var(w, "cos_theta_i", 1, &v->d_i, "", "cosine of the incident zenith angle");
    put_double_att(w, v->v_ci, "simulated_at_0", LSQT_GRID_HORIZON_COS);
    v->v_p = def_var(w, "phi_d", 1, &v->d_p, "rad",
                     "azimuth of the incident direction from the outgoing one (0: same side, backscatter)");
    v->v_co = def_var(w, "cos_theta_o", 1, &v->d_o, "", "cosine of the outgoing zenith angle");
    put_double_att(w, v->v_co, "simulated_at_0", LSQT_GRID_HORIZON_COS);
}

/* The tables and the scalars, per side (from above; from below) and hemisphere
 * (reflection; transmission). */
static void define_tables(ncw *w, const lsqt_state *st, const grid *g, nc_vars *v)
{
    /* with bands every table and scalar leads with channel (dims + 1 without) */
    const int bands = g->nb > 1, dims[4] = {v->d_c, v->d_i, v->d_p, v->d_o}, dims_s[2] = {v->d_c, v->d_o};
    static const char *const scal_long[6] = {
        "directional-hemispherical reflectance", "standard error of R", "directional-hemispherical transmittance",
        "standard error of T", "unscattered forward transmittance (a delta, not in btdf)", "standard error of delta_T"};
    for (int side = 0; side < (g->below ? 2 : 1); side++) {
        const char *suffix = side ? "_below" : "";
        const char *from = side ? ", light entering from below (the stack upside down)" : "";
        for (int h = 0; h < (st->transmits ? 2 : 1); h++)
            for (int e = 0; e < 2; e++) {
                char name[48], long_name[200];
                snprintf(name, sizeof name, "%s%s%s", h ? "btdf" : "brdf", e ? "_stderr" : "", suffix);
                snprintf(long_name, sizeof long_name, "%s%s, not cosine-weighted%s", e ? "standard error of the " : "",
                         h ? "BTDF (transmission)" : "BRDF (reflection)", from);
                v->v_f[side][h][e] = def_var(w, name, 3 + bands, dims + !bands, "sr-1", long_name);
                if (st->wavelengths) put_text(w, v->v_f[side][h][e], "coordinates", "wavelength");
            }
        for (int k = 0; k < 6; k++) {
            char name[48], long_name[200];
            snprintf(name, sizeof name, "%s%s", scal[k], suffix);
            snprintf(long_name, sizeof long_name, "%s%s", scal_long[k], from);
            v->v_s[side][k] = def_var(w, name, 1 + bands, dims_s + !bands, "1", long_name);
            if (st->wavelengths) put_text(w, v->v_s[side][k], "coordinates", "wavelength");
        }
    }
}

/* The run's provenance as global attributes. */
static void put_provenance(ncw *w, const char *input, const lsqt_state *st, const grid *g)
{
    char horizon[160];
    snprintf(horizon, sizeof horizon, "%g (the horizon, cos theta = 0, cannot be simulated)", LSQT_GRID_HORIZON_COS);
    char gridtext[64], paths[32], seed[32], hash[32], version[16];
    snprintf(gridtext, sizeof gridtext, "%d,%d,%d", g->no, g->ni, g->nphi);
    snprintf(paths, sizeof paths, "%llu", (unsigned long long)st->paths);
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)st->seed);
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)st->hash);
    snprintf(version, sizeof version, "%u", st->lss_version);
    put_text(w, NC_GLOBAL, "Conventions", "CF-1.8");
    put_text(w, NC_GLOBAL, "title", "BSDF of a layered assembly (lsqt-cl Monte Carlo simulation)");
    put_text(w, NC_GLOBAL, "source", "lsqt-cl " LSQT_VERSION_STRING);
    put_text(w, NC_GLOBAL, "lss_file", input);
    put_text(w, NC_GLOBAL, "lss_version", version);
    put_text(w, NC_GLOBAL, "assembly", st->canonical);
    put_text(w, NC_GLOBAL, "assembly_hash", hash);
    put_text(w, NC_GLOBAL, "seed", seed);
    put_text(w, NC_GLOBAL, "paths_per_slice", paths);
    put_text(w, NC_GLOBAL, "precision", st->use_double ? "double" : "float");
    put_text(w, NC_GLOBAL, "grid", gridtext);
    put_text(w, NC_GLOBAL, "horizon_simulated_at_cos", horizon);
    put_text(w, NC_GLOBAL, "stderr",
             "one standard error of the mean (batch means over 32 batches); NaN where the paths are too few");
}

/* Every variable's values (est: band after band, as lsqt_estimates gives them). Returns 0,
 * or -1 (out of memory; err filled). */
static int put_values(ncw *w, const lsqt_state *st, const lsqt_slice_est *est, const grid *g, const nc_vars *v,
                      char *err, size_t errcap)
{
    const size_t nb = (size_t)g->nb, table = (size_t)g->ni * (size_t)g->nphi * (size_t)g->no;
    const size_t nax = (size_t)(g->ni > g->nphi ? g->ni : g->nphi), nsc = nb * (size_t)g->no;
    double *ax = malloc(sizeof(double) * (nax > nsc ? nax : nsc));
    double *tab = malloc(sizeof(double) * nb * table);
    const char **labels = calloc(nb, sizeof *labels);
    char (*lab)[32] = malloc(sizeof *lab * nb);
    if (!ax || !tab || !labels || !lab) {
        free(ax), free(tab), free(labels), free(lab);
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    /* the axes carry the nominal grid (Eradiate checks them against linspace) */
    for (int k = 0; k < g->ni; k++) ax[k] = (double)k / (g->ni - 1);
    if (w->status == NC_NOERR) nc_check(w, nc_put_var_double(w->id, v->v_ci, ax), "cos_theta_i values");
    for (int k = 0; k < g->nphi; k++) ax[k] = 2.0 * LSQT_PI * k / g->nphi;
    if (w->status == NC_NOERR) nc_check(w, nc_put_var_double(w->id, v->v_p, ax), "phi_d values");
    for (int k = 0; k < g->no; k++) ax[k] = (double)k / (g->no - 1);
    if (w->status == NC_NOERR) nc_check(w, nc_put_var_double(w->id, v->v_co, ax), "cos_theta_o values");
    if (nb > 1) {
        lsqt_band_names names;
        lsqt_band_names_init(&names, g->nb, st->wavelengths, NULL);
        for (size_t b = 0; b < nb; b++) labels[b] = lsqt_band_label(&names, (int)b, lab[b], sizeof lab[b]);
        if (w->status == NC_NOERR) nc_check(w, nc_put_var_string(w->id, v->v_ch, labels), "channel values");
    }
    if (v->v_wl >= 0 && w->status == NC_NOERR)
        nc_check(w, nc_put_var_double(w->id, v->v_wl, st->wavelengths), "wavelength values");
    const size_t ns = (size_t)st->n_slices;
    for (int side = 0; side < (g->below ? 2 : 1); side++) {
        for (int h = 0; h < (st->transmits ? 2 : 1); h++)
            for (int e = 0; e < 2; e++) {
                for (size_t b = 0; b < nb; b++) fill_table(g, est + b * ns, side, h, e, tab + b * table);
                if (w->status == NC_NOERR)
                    nc_check(w, nc_put_var_double(w->id, v->v_f[side][h][e], tab), "table values");
            }
        for (int k = 0; k < 6; k++) {
            for (size_t b = 0; b < nb; b++)
                for (int ko = 0; ko < g->no; ko++) {
                    const lsqt_slice_est *s = &est[b * ns + (size_t)g->side[side][g->no - 1 - ko]];
                    const lsqt_est *q = k < 2 ? &s->R : k < 4 ? &s->T : &s->delta_T;
                    ax[b * (size_t)g->no + (size_t)ko] = k % 2 ? q->err : q->mean;
                }
            if (w->status == NC_NOERR) nc_check(w, nc_put_var_double(w->id, v->v_s[side][k], ax), scal[k]);
        }
    }
    free(ax), free(tab), free(labels), free(lab);
    return 0;
}

/* Reads back what was written (a writer may miss a full disk): every dimension there. */
static int read_back(const char *tmp, const grid *g, char *err, size_t errcap)
{
    int id, nd = 0, dim_c = -1;
    size_t len_o = 0, len_c = 0;
    if (nc_open(tmp, NC_NOWRITE, &id) != NC_NOERR) {
        snprintf(err, errcap, "'%s' cannot be read back as NetCDF after writing it", tmp);
        return -1;
    }
    int dim_o = -1;
    const int bad = nc_inq_ndims(id, &nd) != NC_NOERR || nd != 3 + (g->nb > 1) ||
                    nc_inq_dimid(id, "cos_theta_o", &dim_o) != NC_NOERR ||
                    nc_inq_dimlen(id, dim_o, &len_o) != NC_NOERR || len_o != (size_t)g->no ||
                    (g->nb > 1 && (nc_inq_dimid(id, "channel", &dim_c) != NC_NOERR ||
                                   nc_inq_dimlen(id, dim_c, &len_c) != NC_NOERR || len_c != (size_t)g->nb));
    nc_close(id);
    if (bad) {
        snprintf(err, errcap, "'%s' does not read back as written", tmp);
        return -1;
    }
    return 0;
}

/* A NetCDF file failed part way and was left open (write_nc): the process must not run
 * HDF5's exit handlers. */
static int g_nc_abandoned;

/* Bytes the file will take, roughly (its values as doubles, plus the headers); the free
 * space of the folder of PATH is checked against it before writing, because a netCDF-4
 * file that meets a full disk is what the library handles worst. Returns 0, or -1 with
 * err filled. */
static int check_room(const char *path, const lsqt_state *st, const grid *g, char *err, size_t errcap)
{
    const double values = (double)g->nb * g->ni * g->nphi * g->no * (st->transmits ? 2 : 1) * (g->below ? 2 : 1) * 2;
    const double need = values * 8.0 + 16384.0 + 64.0 * (g->ni + g->nphi + g->no + g->nb); /* headers: 16 KiB */
    char dir[LSQT_PATH_CAP];
    lsqt_path_folder(path, dir, sizeof dir);
    struct statvfs fs;
    if (statvfs(dir, &fs) != 0 || (double)fs.f_bavail * (double)fs.f_frsize >= need) return 0;
    snprintf(err, errcap, "cannot write '%s': %s (it needs about %.0f bytes, the file system has %.0f free)", path,
             strerror(ENOSPC), need, (double)fs.f_bavail * (double)fs.f_frsize);
    return -1;
}

static int write_nc(const char *tmp, const char *shown, const char *input, const lsqt_state *st, const lsqt_slice_est *est,
                    const grid *g, char *err, size_t errcap)
{
    ncw w = {-1, NC_NOERR, NULL, 0};
    char why[256];
    nc_check(&w, nc_create(tmp, NC_CLOBBER | NC_NETCDF4, &w.id), "create");
    if (w.status != NC_NOERR) {
        snprintf(err, errcap, "cannot create '%s': %s", shown, nc_why(&w, tmp, why, sizeof why));
        return -1;
    }
    nc_vars v;
    define_axes(&w, st, g, &v);
    define_tables(&w, st, g, &v);
    put_provenance(&w, input, st, g);
    if (w.status == NC_NOERR) nc_check(&w, nc_enddef(w.id), "enddef");
    if (put_values(&w, st, est, g, &v, err, errcap)) {
        g_nc_abandoned = 1;
        return -1;
    }
    /* A file that failed is abandoned: closing or aborting it (netCDF 4.9, HDF5 1.10)
     * crashes in HDF5, and so do HDF5's own exit handlers (export_nc then ends with _exit). */
    if (w.status == NC_NOERR) nc_check(&w, nc_close(w.id), "close");
    else g_nc_abandoned = 1;
    if (w.status != NC_NOERR) {
        snprintf(err, errcap, "cannot write '%s' (%s): %s", shown, w.what, nc_why(&w, tmp, why, sizeof why));
        return -1;
    }
    return read_back(tmp, g, err, errcap);
}

/* The grid of ST, or -1 with err saying why it has none. */
static int find_grid(const lsqt_state *st, const char *input, grid *g, char *err, size_t errcap)
{
    memset(g, 0, sizeof *g);
    if (st->dir_method != LSQT_DIRS_GRID) {
        static const char *const how[] = {"--wi-spread", "RRSS", "--wi-file", "--grid", "--rgl-grid"};
        snprintf(err, errcap, "'%s' is not on a grid (its incident directions were chosen by %s): export writes the "
                 "values a run simulated, on their grid; run with --grid NO,NI,NPHI", input,
                 how[st->dir_method <= LSQT_DIRS_RGL ? st->dir_method : 0]);
        return -1;
    }
    if (st->stage != LSQT_STAGE_RUN || st->paths == 0) {
        snprintf(err, errcap, "'%s' holds no finished paths to export (%s)", input,
                 st->stage != LSQT_STAGE_RUN ? "an RRSS pilot shard" : "0 paths");
        return -1;
    }
    g->ni = (int)st->grid_ni, g->nphi = (int)st->grid_nphi, g->na = g->nphi / 2 + 1;
    g->nb = lsqt_state_bands(st);
    int n[2] = {0, 0};
    for (int s = 0; s < st->n_slices; s++) n[(st->slice_flags[s] & LSQT_SLICE_BELOW) != 0]++;
    g->no = n[0], g->below = n[1] > 0;
    if (g->no < 2 || (g->below && n[1] != g->no)) {
        snprintf(err, errcap, "'%s': %d slices from above and %d from below do not make a grid", input, n[0], n[1]);
        return -1;
    }
    for (int side = 0; side < 2; side++) {
        g->side[side] = malloc(sizeof(int) * (size_t)g->no);
        if (!g->side[side]) {
            snprintf(err, errcap, "out of memory");
            return -1;
        }
        int k = 0;
        for (int s = 0; s < st->n_slices; s++)
            if (((st->slice_flags[s] & LSQT_SLICE_BELOW) != 0) == side && k < g->no) g->side[side][k++] = s;
    }
    return 0;
}

/* export --rgl: the tensor file, written as atomically as the NetCDF. */
static int export_rgl(const char *prog, const char *input, const char *out, const lsqt_state *st, int spectral,
                      int quiet)
{
    char msg[LSQT_PATH_CAP * 2 + 256];
    int *slices = malloc(sizeof(int) * (size_t)st->n_slices), rc = 0;
    if (!slices) return lsqt_prog_error(prog, 1, "out of memory");
    const int nt = lsqt_rgl_slices(st, input, slices, msg, sizeof msg);
    if (nt < 0 || lsqt_rgl_bands(st, input, spectral, msg, sizeof msg)) {
        free(slices);
        return lsqt_prog_error(prog, 2, msg);
    }
    lsqt_slice_est *est = lsqt_estimates(st);
    lsqt_out o;
    if (!est) rc = lsqt_prog_error(prog, 1, "out of memory");
    else if (lsqt_out_open_named(&o, out, msg, sizeof msg)) rc = lsqt_prog_error(prog, 1, msg);
    else if (lsqt_rgl_write(lsqt_out_name(&o), st, est, slices, nt, spectral, msg, sizeof msg)) {
        lsqt_out_abort(&o);
        rc = lsqt_prog_error(prog, 1, msg);
    } else if (lsqt_out_commit_named(&o, msg, sizeof msg)) {
        rc = lsqt_prog_error(prog, 1, msg);
    } else if (!quiet) {
        char what[96] = "";
        if (st->n_bands > 1 && spectral)
            snprintf(what, sizeof what, "spectral: %d wavelengths, %g to %g nm", st->n_bands, st->wavelengths[0],
                     st->wavelengths[st->n_bands - 1]);
        else if (st->n_bands > 1)
            snprintf(what, sizeof what, "rgb: %s", st->wavelengths ? "linear sRGB of the spectrum" : "R, G, B");
        printf("wrote %s: RGL tensor file (%s), reflection from above at %d theta_i x %u x %u half vectors, %llu paths "
               "per slice\n", out, what[0] ? what : spectral ? "spectral: wavelengths, spectra" : "rgb", nt,
               st->grid_ni, st->grid_ni, (unsigned long long)st->paths);
    }
    if (est) lsqt_estimates_free(est, st->n_slices);
    free(slices);
    return rc;
}

/* What the command line asks. */
typedef struct export_args {
    const char *input, *out;
    int quiet, rgl; /* rgl 1: --rgl, 2: --rgl-spectral */
} export_args;

/* The flags and files. Returns -1 to go on, else the exit status (printed). */
static int parse_args(const char *prog, int argc, char **argv, export_args *x)
{
    memset(x, 0, sizeof *x);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout, prog);
            return 0;
        } else if (strcmp(a, "--version") == 0) {
            printf("%s %s\n", prog, lsqt_version());
            return 0;
        } else if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
            x->quiet = 1;
        } else if (strcmp(a, "--rgl") == 0 || strcmp(a, "--rgl-spectral") == 0) {
            if (x->rgl) return lsqt_prog_error(prog, 2, "--rgl and --rgl-spectral: give one of them");
            x->rgl = a[5] ? 2 : 1;
        } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
            if (i + 1 >= argc) return lsqt_prog_error(prog, 2, "-o needs a file name (OUT.nc)");
            x->out = argv[++i];
        } else if (strncmp(a, "--output=", 9) == 0) {
            x->out = a + 9;
        } else if (a[0] == '-' && a[1]) {
            char msg[160];
            snprintf(msg, sizeof msg, "unknown option '%.64s' (see %s --help)", a, prog);
            return lsqt_prog_error(prog, 2, msg);
        } else if (x->input) {
            return lsqt_prog_error(prog, 2, "more than one input LSS");
        } else {
            x->input = a;
        }
    }
    if (!x->input || !x->out || !*x->out) {
        usage(stderr, prog);
        return 2;
    }
    return -1;
}

/* The output's name and place: its extension, a regular file (it is read back), not the
 * input. Returns 0 or 2 (printed). */
static int check_output(const char *prog, const export_args *x)
{
    const char *input = x->input, *out = x->out;
    const int rgl = x->rgl;
    const size_t ol = strlen(out);
    if (!rgl && (ol < 4 || strcmp(out + ol - 3, ".nc") != 0))
        return lsqt_prog_error(prog, 2, "the output's name must end in .nc (NetCDF; --rgl writes an RGL tensor file, OUT.bsdf)");
    if (rgl && (ol < 6 || strcmp(out + ol - 5, ".bsdf") != 0))
        return lsqt_prog_error(prog, 2, "with --rgl the output's name must end in .bsdf (an RGL tensor file)");
    const char *what = NULL;
    if (strcmp(out, "-") == 0 || lsqt_path_type(out, &what) > LSQT_PATH_REGULAR) {
        char msg[LSQT_PATH_CAP + 96];
        snprintf(msg, sizeof msg, "'%s' is %s%s: %s is written to a regular file (it is read back)", out,
                 what ? "a " : "", what ? what : "stdout", rgl ? "a tensor file" : "NetCDF");
        return lsqt_prog_error(prog, 2, msg);
    }
    if (strcmp(input, "-") != 0 && lsqt_same_file(out, input)) {
        char msg[LSQT_PATH_CAP + 64];
        snprintf(msg, sizeof msg, "the output '%s' would replace the input", out);
        return lsqt_prog_error(prog, 2, msg);
    }
    return 0;
}

/* A grid state as NetCDF, written through a temporary with its extension. */
static int export_nc(const char *prog, const char *input, const char *out, const lsqt_state *st, int quiet)
{
    char msg[LSQT_PATH_CAP * 2 + 256];
    grid g;
    if (find_grid(st, input, &g, msg, sizeof msg)) {
        free(g.side[0]), free(g.side[1]);
        return lsqt_prog_error(prog, 2, msg);
    }
    int rc = 0;
    lsqt_slice_est *est = lsqt_estimates(st);
    lsqt_out o;
    if (!est) rc = lsqt_prog_error(prog, 1, "out of memory");
    else if (check_room(out, st, &g, msg, sizeof msg)) rc = lsqt_prog_error(prog, 1, msg);
    else if (lsqt_out_open_named(&o, out, msg, sizeof msg)) rc = lsqt_prog_error(prog, 1, msg);
    else if (write_nc(lsqt_out_name(&o), out, input, st, est, &g, msg, sizeof msg)) {
        lsqt_out_abort(&o);
        rc = lsqt_prog_error(prog, 1, msg);
    } else if (lsqt_out_commit_named(&o, msg, sizeof msg)) {
        rc = lsqt_prog_error(prog, 1, msg);
    } else if (!quiet) {
        char chan[80] = "";
        if (g.nb > 1) {
            char l0[32], l1[32];
            snprintf(chan, sizeof chan, "channel %d: %s to %s, ", g.nb, lsqt_band_label_one(g.nb, st->wavelengths, 0, l0, sizeof l0),
                     lsqt_band_label_one(g.nb, st->wavelengths, g.nb - 1, l1, sizeof l1));
        }
        printf("wrote %s: brdf%s over (%scos_theta_i %d, phi_d %d, cos_theta_o %d)%s, %llu paths per slice\n", out,
               st->transmits ? " and btdf" : "", chan, g.ni, g.nphi, g.no, g.below ? " from above and from below" : "",
               (unsigned long long)st->paths);
    }
    if (est) lsqt_estimates_free(est, st->n_slices);
    free(g.side[0]), free(g.side[1]);
    if (g_nc_abandoned) { /* the temporary is gone (lsqt_out_abort); HDF5 must not see exit */
        fflush(stdout), fflush(stderr);
        _exit(rc);
    }
    return rc;
}

int lsqt_export_main(const char *prog, int argc, char **argv)
{
    signal(SIGPIPE, SIG_IGN);
    export_args x;
    int rc = parse_args(prog, argc, argv, &x);
    if (rc >= 0) return rc;
    if ((rc = check_output(prog, &x))) return rc;
    char msg[LSQT_PATH_CAP * 2 + 256];
    lsqt_state st;
    if (lsqt_lss_read(x.input, &st, msg, sizeof msg)) return lsqt_prog_error(prog, 2, msg);
    rc = x.rgl ? export_rgl(prog, x.input, x.out, &st, x.rgl == 2, x.quiet)
               : export_nc(prog, x.input, x.out, &st, x.quiet);
    lsqt_state_free(&st);
    return rc;
}
