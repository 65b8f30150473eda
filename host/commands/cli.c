#include "lsqt/cli.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/util.h"

/* --help, part 1: the usage lines, what a run does, and the flags that choose its directions. */
static void help_usage_and_sampling(FILE *f)
{
    fputs("usage: lsqt-cl [OPTIONS] FILE|-\n"
          "       lsqt-cl merge OUT.lss IN.lss... [-o RAW] [-H] [--json PATH] [--partial] [-q]\n"
          "       lsqt-cl info FILE.lss [--json PATH]   (the same: lssinfo FILE.lss [--json PATH])\n"
          "       lsqt-cl export FILE.lss -o OUT.nc     (an LSS made with --grid, as NetCDF)\n"
          "       lsqt-cl export FILE.lss -o OUT.bsdf --rgl|--rgl-spectral  (--rgl-grid: RGL tensor)\n"
          "Simulates the emergent BSDF of a layered assembly (LSQT file; - reads stdin) with\n"
          "OpenCL, writing FILE.raw for raw2sqt and FILE.lss (progressive state: running again\n"
          "adds paths to it, with the sampling it was made with: a flag that contradicts it is an\n"
          "error, -R starts over; one run at a time owns it, through FILE.lss.lock).\n"
          "\n"
          "  -p, --path-count N          paths per outgoing direction (default 10000; 1e7 is fine);\n"
          "                              continuing an LSS, the paths to add\n"
          "      --plan                  two short runs (seconds) in a temporary folder, then the\n"
          "                              time per 1e6 paths and, per slice, the paths a target\n"
          "                              error needs (error ~ 1/sqrt(paths)); writes nothing here\n"
          "      --total-paths N         instead of -p: the paths per slice the LSS is to hold; a\n"
          "                              fresh run does N, a continued one adds what is missing\n"
          "                              (none when it holds N), so rerunning a stopped command\n"
          "                              finishes it\n"
          "  -wo, --wo-count N           outgoing directions (slices), 4-1024 (default 12)\n"
          "      --wo-angles=A,B,...     explicit outgoing angles in degrees, [0, 90)\n"
          "  -wi, --wi-count N           incident directions per slice, 16-1024 (default 80), chosen\n"
          "                              by RRSS from the slice's own walks (even with --wi-spread\n"
          "                              when the stack transmits)\n"
          "      --wi-file FILE          the incident directions, the same for every slice,\n"
          "                              instead of -wi: 1-1024, one a line, 'x y z' (normalised)\n"
          "                              or 'theta_deg phi_deg' (theta from +z in [0, 180], phi\n"
          "                              from +x, the azimuth of wo); '#' comments. Not on the\n"
          "                              horizon (z = 0), nor below it unless the stack transmits.\n"
          "                              The BSDF is mirror symmetric about the plane of wo (xz):\n"
          "                              a direction with y < 0 is simulated at (x, -y, z), and\n"
          "                              the RAW, which holds both mirror images, has it as given\n"
          "  -rx, --rrss-oversampling N  RRSS candidates per incident direction, 2-8 (default 4)\n"
          "  -rp, --rrss-path-frac F     share of the first run's -p spent on the RRSS pilot, (0,1]\n"
          "                              (default 0.3; its tallies are kept)\n"
          "      --wi-spread             an even spread of incident directions instead of RRSS\n"
          "      --grid NO,NI,NPHI       a regular grid instead of -wo and -wi (for NetCDF and\n"
          "                              Eradiate): slices at cos(theta_o) = linspace(0, 1, NO),\n"
          "                              directions at cos(theta_i) = linspace(0, 1, NI) (and\n"
          "                              below, when the stack transmits) times the azimuths\n"
          "                              2 pi k / NPHI in [0, pi] (the rest are their mirror\n"
          "                              images); cos 0, the horizon, is simulated at 0.001.\n"
          "                              --grid N is N,N,4(N-1). NO, NI >= 2, NPHI >= 2, even\n"
          "      --rgl-grid NT,NU        the nodes of an RGL tensor file (export --rgl, for Mitsuba\n"
          "                              3 and pbrt-v4) instead of -wo and -wi: NT slices at\n"
          "                              theta = linspace(0, 90 deg, NT), each with the reflections\n"
          "                              of wo about an NU x NU grid of half vectors (theta_m =\n"
          "                              u^2 90 deg, phi_m = 360 deg v - 180 deg from wo's, u and v\n"
          "                              on linspace(0, 1, NU)); NT 2-1024, NU 2-44\n"
          , f);
    fputs("      --max-memory SIZE       refuse (exit 2, before simulating) a run whose estimated\n"
          "                              peak memory exceeds SIZE (e.g. 500M, 8G; 0: no limit;\n"
          "                              default 80 % of the memory available); --plan shows it\n",
          f);
}

/* --help, part 2: the flags of the sides, the seed, the device and the outputs. */
static void help_run_flags(FILE *f)
{
    fputs("      --wavelengths LIST      the run's bands, in nm: 450,550,650 or START:STOP:STEP (both\n"
          "                              ends included); a number key may then be a comma list (one\n"
          "                              value per band) or @FILE (a table of nm and value, read\n"
          "                              at each band); without it, comma lists alone set the bands\n"
          "                              (three are R, G, B). One RAW per band: OUT.550nm.raw\n"
          "                              (one band at one wavelength: OUT.raw, which records it)\n"
          ,f);
    fputs("      --from-below            when the stack transmits, also the slices of light entering\n"
          "                              from the bottom medium (the full two-sided BSDF), written\n"
          "                              to OUT.below.raw (the stack turned upside down: negate z of\n"
          "                              wo and wi for its own frame) and flagged in the LSS; OUT\n"
          "                              stays as without it\n"
          "  -R, --restart               ignore an existing LSS and start over\n"
          "  -s, --seed N                random seed, an integer in 0 to 2^64-1 (default 0)\n"
          "  -t, --thread-count N        threads of a CPU (PoCL) device (default: all; other\n"
          "                              OpenCL drivers ignore it)\n"
          "  -o, --output PATH           RAW file (default FILE.raw, Layered.raw for stdin; - is stdout)\n"
          "  -H, --only-hemispherical    write OUT.R.raw and OUT.T.raw (transmission mirrored up)\n"
          "                              instead, named by replacing OUT's final .raw\n"
          "      --no-raw                write no RAW file (the LSS, --json and lsqt-cl export\n"
          "                              hold the results: for runs of many bands)\n"
          "  -d, --device D              OpenCL device: index, name substring, cpu or gpu\n"
          "      --list-devices          list OpenCL devices and exit\n"
          "      --double                compute in double precision (device needs fp64)\n"
          , f);
}

/* --help, part 3: the stop rules, shards, the other flags, and the notes on subcommands, outputs,
 * the environment and the exit status. */
static void help_stops_and_notes(FILE *f)
{
    fputs("      --time-limit S          stop adding paths after S seconds\n"
          "      --checkpoint S          write the LSS every S seconds during a run (default 300,\n"
          "                              0: never; in the RRSS pilot it holds the pilot). SIGINT,\n"
          "                              SIGTERM, SIGHUP and SIGUSR1 finish the launch, write LSS\n"
          "                              and RAW and exit 1; continuing gives the uninterrupted\n"
          "                              bytes (from the pilot too: it finishes the pilot first)\n"
          "      --target-error E        add paths until every slice's largest relative standard\n"
          "                              error of the BSDF values is at most E (e.g. 0.01); -p,\n"
          "                              if given, is then a cap (checked at path counts that\n"
          "                              depend only on the tallies: the stop is reproducible)\n"
          "      --lss PATH              LSS file (default FILE.lss; none for stdin)\n"
          "      --shard K/N             run the K-th of N disjoint parts of this run's paths\n"
          "                              (0 <= K < N), continuing the LSS (if any) but writing\n"
          "                              only the part, to LSS.shard-K-of-N.lss (no RAW unless\n"
          "                              -o). A fresh RRSS run's shards run only the pilot\n"
          "      --refine                with --shard: only the paths the state owes (the rest\n"
          "                              of the run after a merged RRSS pilot), else nothing\n"
          "                              Steps: shards, lsqt-cl merge, shards --refine, merge\n"
          "                              (lsqt-local-shards, lsqt-slurm-submit when installed;\n"
          "                              tools/slurm/local-shards.sh, submit.sh in the source)\n"
          "      --json PATH             machine-readable summary\n"
          "  -q, --quiet                 print errors only\n"
          "  -v, --verbose               print more (device, kernel build options, launches)\n"
          "  -h, --help                  this text\n"
          "      --version               the version, the commit it was built from, and the\n"
          "                              OpenCL devices (fp64: those that run --double)\n"
          "lsqt-cl merge OUT.lss IN.lss... adds the tallies of parts of one run (shards) and\n"
          "writes OUT.lss and its RAW; see lsqt-cl merge --help.\n"
          "lsqt-cl export writes the BSDF of a --grid LSS with its standard errors as NetCDF\n"
          "(xarray, Eradiate); see lsqt-cl export --help.\n"
          "lsqt-cl info prints what an LSS holds (format, assembly, hash, seed, precision, flags,\n"
          "path ranges, per-slice R, T, delta_T with errors) without OpenCL; --json writes it as\n"
          "JSON (- is stdout). See lsqt-cl info --help.\n"
          "Flags take their value as the next argument or after '=' (-wi 300, -wi=300).\n"
          "Outputs: a regular file is replaced atomically (through a symlink, its target is);\n"
          "a device, FIFO or socket is written in place (-o /dev/null discards). An LSS path\n"
          "that is not a regular file is never read: use -R to write a fresh state into it.\n"
          "Environment: LSQT_VECTOR_WIDTH=2|4|8|16 sets how many directions next-event\n"
          "estimation evaluates at once (default 16 on a CPU, 2 on a GPU; the result does\n"
          "not depend on it); LSQT_GPU_PATH=1 runs the GPU code path on any device (vector\n"
          "width 2, work-groups of 64, one RNG block at a time: how the tests check it on a\n"
          "CPU), =0 the CPU's; LSQT_BAND_BLOCK=1..16 (default 16; the GPU code path takes at\n"
          "most 4) is the most bands that share their paths (1: every band on paths of its\n"
          "own, as its one-band run); LSQT_BAND_DIVERGENCE=D (default: a model of what\n"
          "sharing pays; inf: no limit) how far apart the paths of bands that share may\n"
          "be; PoCL reads\n"
          "its own (POCL_CACHE_DIR, POCL_CPU_MAX_CU_NUM, ...).\n"
          "Exit status: 0 success, 1 failure, 2 bad input or flags, 3 no usable OpenCL device.\n",
          f);
}

void lsqt_cli_help(FILE *f)
{
    help_usage_and_sampling(f);
    help_run_flags(f);
    help_stops_and_notes(f);
}

/* --max-memory SIZE: bytes, with K, M, G or T (binary; a trailing B allowed), e.g.
 * 500M, 1.5G. Returns 0 or -1. */
static int parse_size(const char *v, uint64_t *out)
{
    char *end = NULL;
    const double x = strtod(v, &end);
    if (end == v || !(x >= 0) || x > 1e18) return -1;
    const char *u = "KMGT", *k = *end ? strchr(u, toupper((unsigned char)*end)) : NULL;
    double scale = 1;
    if (*end) {
        if (!k) return -1;
        scale = ldexp(1.0, 10 * (int)(k - u + 1));
        end++;
        if (*end == 'B' || *end == 'b') end++;
    }
    if (*end || x * scale > 1.8e19) return -1;
    *out = (uint64_t)(x * scale);
    return 0;
}

enum flag_id {
    F_MAX_MEMORY,
    F_PATHS, F_WO, F_WO_ANGLES, F_WI, F_WI_FILE, F_RX, F_RP, F_RESTART, F_SEED, F_THREADS, F_OUTPUT,
    F_HEMI, F_SPREAD, F_GRID, F_RGL_GRID, F_WAVELENGTHS, F_BELOW, F_CHECKPOINT, F_SHARD, F_REFINE, F_DEVICE, F_LIST, F_DOUBLE, F_TIME, F_TARGET, F_LSS, F_JSON, F_QUIET, F_VERBOSE, F_HELP, F_VERSION, F_TOTAL, F_PLAN, F_NO_RAW
};

static const struct flag {
    const char *short_name, *long_name;
    int id, takes_value;
} flags[] = {
    {NULL, "--max-memory", F_MAX_MEMORY, 1},
    {"-p", "--path-count", F_PATHS, 1},      {"-wo", "--wo-count", F_WO, 1},
    {NULL, "--wo-angles", F_WO_ANGLES, 1},   {"-wi", "--wi-count", F_WI, 1},
    {NULL, "--wi-file", F_WI_FILE, 1},
    {"-rx", "--rrss-oversampling", F_RX, 1}, {"-rp", "--rrss-path-frac", F_RP, 1},
    {"-R", "--restart", F_RESTART, 0},       {"-s", "--seed", F_SEED, 1},
    {"-t", "--thread-count", F_THREADS, 1},  {"-o", "--output", F_OUTPUT, 1},
    {"-H", "--only-hemispherical", F_HEMI, 0}, {"-d", "--device", F_DEVICE, 1},
    {NULL, "--list-devices", F_LIST, 0},     {NULL, "--double", F_DOUBLE, 0},
    {NULL, "--time-limit", F_TIME, 1},       {NULL, "--lss", F_LSS, 1},
    {NULL, "--json", F_JSON, 1},             {"-q", "--quiet", F_QUIET, 0},
    {"-v", "--verbose", F_VERBOSE, 0},       {"-h", "--help", F_HELP, 0},
    {NULL, "--target-error", F_TARGET, 1},  {NULL, "--wi-spread", F_SPREAD, 0},
    {NULL, "--checkpoint", F_CHECKPOINT, 1}, {NULL, "--shard", F_SHARD, 1},
    {NULL, "--refine", F_REFINE, 0}, {NULL, "--from-below", F_BELOW, 0},
    {NULL, "--grid", F_GRID, 1},             {NULL, "--rgl-grid", F_RGL_GRID, 1},
    {NULL, "--wavelengths", F_WAVELENGTHS, 1}, {NULL, "--version", F_VERSION, 0},
    {NULL, "--total-paths", F_TOTAL, 1},     {NULL, "--plan", F_PLAN, 0},
    {NULL, "--no-raw", F_NO_RAW, 0},
};

/* --grid NO,NI,NPHI or --grid N (= N,N,4(N-1)): NO, NI in 2-1024, NPHI even in 2-2048
 * (what fits in 1024 directions is checked once the stack is known). */
static int parse_grid(const char *v, lsqt_cli *c)
{
    char buf[64];
    if (strlen(v) >= sizeof buf) return -1;
    strcpy(buf, v);
    uint64_t n[3];
    int k = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ","))
        if (k >= 3 || lsqt_parse_count(tok, 2, 2048, &n[k++])) return -1;
    if (k == 1) n[1] = n[0], n[2] = 4 * (n[0] - 1);
    else if (k != 3) return -1;
    if (n[0] > 1024 || n[1] > 1024 || n[2] % 2) return -1;
    c->grid_no = (int)n[0], c->grid_ni = (int)n[1], c->grid_nphi = (int)n[2];
    return 0;
}

/* --rgl-grid NT,NU: NT slices in 2-1024, NU in 2-44 (NU - NU/2 rows of NU directions
 * fit in the 1024 a slice can have). Kept as a grid of NT slices and NI = NU, NPHI 0. */
static int parse_rgl_grid(const char *v, lsqt_cli *c)
{
    const char *comma = strchr(v, ',');
    char nt[32];
    uint64_t t, u;
    if (!comma || comma - v >= (long)sizeof nt) return -1;
    memcpy(nt, v, (size_t)(comma - v));
    nt[comma - v] = '\0';
    if (lsqt_parse_count(nt, 2, 1024, &t) || lsqt_parse_count(comma + 1, 2, 44, &u)) return -1;
    c->grid_no = (int)t, c->grid_ni = (int)u, c->grid_nphi = 0, c->grid_rgl = 1;
    return 0;
}

/* --shard K/N: 0 <= K < N <= 65536, decimal digits only. */
static int parse_shard(const char *v, lsqt_cli *c)
{
    const char *slash = strchr(v, '/');
    if (!slash || slash == v || !slash[1] || slash - v > 10) return -1;
    char k[16];
    memcpy(k, v, (size_t)(slash - v));
    k[slash - v] = '\0';
    uint64_t kk, nn;
    if (lsqt_parse_u64(k, &kk) || lsqt_parse_u64(slash + 1, &nn) || nn < 1 || nn > 65536 || kk >= nn) return -1;
    c->shard_k = (int)kk, c->shard_n = (int)nn;
    return 0;
}

static int parse_angles(const char *s, lsqt_cli *c)
{
    char buf[8192];
    if (strlen(s) >= sizeof buf) return -1;
    strcpy(buf, s);
    c->n_wo_angles = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        double deg;
        if (c->n_wo_angles >= LSQT_MAX_WO || lsqt_parse_double(tok, &deg) || deg < 0 || deg >= 90)
            return -1;
        c->wo_angles[c->n_wo_angles++] = deg * LSQT_PI / 180.0;
    }
    return c->n_wo_angles > 0 ? 0 : -1;
}

/* Applies one flag's value; returns 0 or fills err. */
static int apply(const struct flag *fl, const char *name, const char *v, lsqt_cli *c, char *err,
                 size_t errcap)
{
    uint64_t n = 0;
    double d = 0;
    int both = 0;
    const char *expect = NULL;
    switch (fl->id) {
    case F_PATHS: if (lsqt_parse_count(v, 1, 9.0e15, &c->paths)) expect = "an integer path count from 1 to 9e15 (e.g. 10000 or 1e7)"; c->paths_given = 1; break;
    case F_WO: if (lsqt_parse_count(v, 4, 1024, &n)) expect = "an integer in 4-1024"; else c->wo_count = (int)n; c->wo_given = c->sampling_given = 1; break;
    case F_WO_ANGLES: if (parse_angles(v, c)) expect = "comma-separated angles in degrees in [0, 90), at most 1024"; c->sampling_given = 1; break;
    case F_WI: if (lsqt_parse_count(v, 16, 1024, &n)) expect = "an integer in 16-1024"; else c->wi_count = (int)n; c->wi_given = c->sampling_given = 1; break;
    case F_WI_FILE: if (!*v) expect = "a file of directions"; c->wi_file = v; c->sampling_given = 1; break;
    case F_RX: if (lsqt_parse_count(v, 2, 8, &n)) expect = "an integer in 2-8"; else c->rx = (int)n; c->rx_given = c->sampling_given = 1; break;
    case F_RP: if (lsqt_parse_double(v, &d) || !(d > 0 && d <= 1)) expect = "a number in (0, 1]"; else c->rp = d; c->rp_given = c->sampling_given = 1; break;
    case F_MAX_MEMORY: if (parse_size(v, &c->max_memory)) expect = "a size such as 500M, 8G or 0 (no limit)"; else c->max_memory_given = 1; break;
    case F_SEED: if (lsqt_parse_u64(v, &c->seed)) expect = "an integer in 0-18446744073709551615 (decimal digits)"; c->seed_given = c->sampling_given = 1; break;
    case F_THREADS: if (lsqt_parse_count(v, 1, 4096, &n)) expect = "an integer in 1-4096"; else c->threads = (int)n; break;
    case F_TIME: if (lsqt_parse_double(v, &d) || !(d > 0)) expect = "a positive number of seconds"; else c->time_limit = d; break;
    case F_TARGET: if (lsqt_parse_double(v, &d) || !(d > 0)) expect = "a positive relative error (e.g. 0.01)"; else c->target_error = d; break;
    case F_OUTPUT: if (!*v) expect = "a file name"; c->output = v; break;
    case F_DEVICE: if (!*v) expect = "an index, a name substring, cpu or gpu"; c->device = v; break;
    case F_LSS: if (!*v) expect = "a file name"; c->lss = v; break;
    case F_JSON: if (!*v) expect = "a file name"; c->json = v; break;
    case F_RESTART: c->restart = 1; break;
    case F_HEMI: c->only_hemispherical = 1; break;
    case F_NO_RAW: c->no_raw = 1; break;
    case F_SPREAD: c->wi_spread = 1; c->sampling_given = 1; break;
    case F_RGL_GRID: both = c->grid_no && !c->grid_rgl;
        if (parse_rgl_grid(v, c)) expect = "NT,NU: NT slices in 2-1024, NU (half vectors per axis) in 2-44";
        c->grid_rgl = both ? 2 : c->grid_rgl, c->sampling_given = 1; break;
    case F_GRID: both = c->grid_rgl != 0;
        if (both) c->grid_rgl = 2;
        if (parse_grid(v, c)) expect = "NO,NI,NPHI (or N for N,N,4(N-1)): NO and NI in 2-1024, NPHI even in 2-2048";
        c->sampling_given = 1; break;
    case F_WAVELENGTHS: if (!*v) expect = "wavelengths in nm: a list (450,550,650) or START:STOP:STEP"; c->wavelengths = v; break;
    case F_BELOW: c->from_below = 1; c->sampling_given = 1; break;
    case F_CHECKPOINT: if (lsqt_parse_double(v, &d) || !(d >= 0)) expect = "seconds >= 0 (0: no checkpoints)"; else c->checkpoint = d; break;
    case F_SHARD: if (parse_shard(v, c)) expect = "K/N with 0 <= K < N <= 65536 (e.g. 0/4; SLURM: $SLURM_ARRAY_TASK_ID/N)"; break;
    case F_REFINE: c->refine = 1; break;
    case F_LIST: c->list_devices = 1; break;
    case F_DOUBLE: c->use_double = 1; break;
    case F_QUIET: c->quiet = 1; break;
    case F_VERBOSE: c->verbose = 1; break;
    case F_HELP: c->help = 1; break;
    case F_VERSION: c->version = 1; break;
    case F_PLAN: c->plan = 1; break;
    case F_TOTAL: if (lsqt_parse_count(v, 1, 9.0e15, &c->total_paths)) expect = "an integer path count from 1 to 9e15 (e.g. 10000 or 1e7)"; break;
    default: break;
    }
    if (expect) {
        snprintf(err, errcap, "bad value '%.64s' for %s: expected %s", v, name, expect);
        return 2;
    }
    return 0;
}

/* The value of the flag at argv[*i] (the next argument, or after '='), applied to c;
 * *i moves past what it read. wi_name: -wi or --wi-count, as given. Returns 0 or 2. */
static int read_flag(int argc, char **argv, int *i, lsqt_cli *c, char wi_name[16], char *err, size_t errcap)
{
    const char *a = argv[*i];
    if (a[0] != '-' || strcmp(a, "-") == 0) {
        if (c->input) {
            snprintf(err, errcap, "more than one input file: '%.200s' and '%.200s'", c->input, a);
            return 2;
        }
        c->input = a;
        return 0;
    }
    /* "-wi=300" and "--wi-count=300" carry their value after '='. */
    char name[64];
    const char *eq = strchr(a, '=');
    size_t nl = eq ? (size_t)(eq - a) : strlen(a);
    if (nl >= sizeof name) nl = sizeof name - 1;
    memcpy(name, a, nl);
    name[nl] = '\0';
    const struct flag *fl = NULL;
    for (size_t k = 0; k < sizeof flags / sizeof *flags && !fl; k++)
        if ((flags[k].short_name && strcmp(name, flags[k].short_name) == 0) ||
            strcmp(name, flags[k].long_name) == 0)
            fl = &flags[k];
    if (!fl) {
        const char *names[2 * sizeof flags / sizeof *flags];
        int nn = 0;
        for (size_t k = 0; k < sizeof flags / sizeof *flags; k++) {
            if (flags[k].short_name) names[nn++] = flags[k].short_name;
            names[nn++] = flags[k].long_name;
        }
        const char *near = lsqt_closest(name, strlen(name), names, nn);
        if (near) snprintf(err, errcap, "unknown option '%.64s' (did you mean '%s'? see --help)", a, near);
        else snprintf(err, errcap, "unknown option '%.64s' (see --help)", a);
        return 2;
    }
    const char *v = NULL;
    if (fl->takes_value) {
        if (eq) v = eq + 1;
        else if (*i + 1 < argc) v = argv[++*i];
        else {
            snprintf(err, errcap, "%s needs a value (see --help)", name);
            return 2;
        }
    } else if (eq) {
        snprintf(err, errcap, "%s takes no value", name);
        return 2;
    }
    if (fl->id == F_WI)
        snprintf(wi_name, 16, "%s", fl->short_name && strcmp(name, fl->short_name) == 0 ? "-wi" : "--wi-count");
    return apply(fl, name, v ? v : "", c, err, errcap);
}

/* Flags that choose one thing two ways: an error, not a silent pick. Returns 0 or 2. */
static int check_choices(const lsqt_cli *c, const char *wi_name, char *err, size_t errcap)
{
    if (wi_name[0] && c->wi_file) {
        snprintf(err, errcap, "%s and --wi-file both set the incident directions: give one of them", wi_name);
        return 2;
    }
    /* RRSS (the default) chooses the directions; --wi-spread and --wi-file choose them
     * otherwise: two choices in one command are an error, not a silent pick. */
    if (c->wi_spread && c->wi_file) {
        snprintf(err, errcap, "--wi-spread and --wi-file both choose the incident directions: give one of them");
        return 2;
    }
    if ((c->rx_given || c->rp_given) && (c->wi_spread || c->wi_file)) {
        snprintf(err, errcap, "%s sets RRSS's pilot, and %s chooses the directions without RRSS: drop one of them",
                 c->rx_given ? "-rx" : "-rp", c->wi_file ? "--wi-file" : "--wi-spread");
        return 2;
    }
    /* --grid fixes the slices and the directions: any other choice of them contradicts it. */
    if (c->grid_rgl == 2) {
        snprintf(err, errcap, "--grid and --rgl-grid both set the slices and the incident directions: give one of them");
        return 2;
    }
    if (c->grid_no) {
        const char *other = c->wo_given ? "-wo" : c->n_wo_angles ? "--wo-angles" : wi_name[0] ? wi_name
                          : c->wi_file ? "--wi-file" : c->wi_spread ? "--wi-spread" : c->rx_given ? "-rx"
                          : c->rp_given ? "-rp" : NULL;
        if (other) {
            snprintf(err, errcap, "%s sets the slices and the incident directions, and %s chooses them too: give one "
                                  "of them", c->grid_rgl ? "--rgl-grid" : "--grid", other);
            return 2;
        }
    }
    if (c->plan && c->shard_n) {
        snprintf(err, errcap, "--plan predicts a whole run: drop --shard");
        return 2;
    }
    if (c->total_paths && (c->paths_given || c->shard_n)) {
        snprintf(err, errcap, "--total-paths sets how many paths the LSS is to hold, and %s %s: give one of them",
                 c->paths_given ? "-p" : "--shard", c->paths_given ? "how many to add" : "splits a run of -p paths");
        return 2;
    }
    if (c->refine && !c->shard_n) {
        snprintf(err, errcap, "--refine is for the refinement shards of a sharded run: give --shard K/N too");
        return 2;
    }
    if (c->shard_n && c->target_error > 0) {
        snprintf(err, errcap, "--target-error cannot stop a shard (the merged error is not known to it): "
                              "give the shards -p, or run in one process");
        return 2;
    }
    if (c->wi_file && c->input && strcmp(c->wi_file, "-") == 0 && strcmp(c->input, "-") == 0) {
        snprintf(err, errcap, "--wi-file - and the input - cannot both be read from stdin");
        return 2;
    }
    return 0;
}

int lsqt_cli_parse(int argc, char **argv, lsqt_cli *c, char *err, size_t errcap)
{
    memset(c, 0, sizeof *c);
    c->paths = 10000;
    c->wo_count = 12;
    c->wi_count = 80;
    c->rx = 4;
    c->rp = 0.3;
    c->checkpoint = 300;
    char wi_name[16] = ""; /* -wi or --wi-count, as given */
    for (int i = 1; i < argc; i++) {
        int rc = read_flag(argc, argv, &i, c, wi_name, err, errcap);
        if (rc) return rc;
    }
    return check_choices(c, wi_name, err, errcap);
}
