/* Command-line flags of lsqt-cl (docs/guide.md). */
#ifndef LSQT_CLI_H
#define LSQT_CLI_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LSQT_MAX_WO 1024

enum { LSQT_PLAN_CALIBRATION = 2 };

typedef struct lsqt_cli {
    const char *input;        /* file or "-" */
    uint64_t paths;           /* -p, per slice */
    int wo_count, wi_count;   /* -wo, -wi */
    const char *wi_file;      /* --wi-file: the incident directions, instead of -wi */
    double wo_angles[LSQT_MAX_WO]; /* --wo-angles, radians */
    int n_wo_angles;
    int rx;                   /* -rx */
    int wi_spread;            /* --wi-spread: the even spread instead of RRSS */
    double rp;                /* -rp */
    uint64_t max_memory;      /* --max-memory: bytes a run may use (0: no limit); max_memory_given */
    int max_memory_given;
    int restart;              /* -R */
    uint64_t seed;            /* -s */
    int seed_given;
    int threads;              /* -t, 0 = all */
    const char *output;       /* -o RAW path */
    int only_hemispherical;   /* -H */
    int no_raw;               /* --no-raw: no RAW file at all */
    const char *device;       /* -d */
    int list_devices;
    int use_double;
    double time_limit;        /* seconds, 0 = none */
    double target_error;      /* --target-error, 0 = none */
    double checkpoint;        /* --checkpoint seconds, 0 = never (default 300) */
    int paths_given;          /* -p was given */
    uint64_t total_paths;     /* --total-paths N: the paths per slice the LSS is to hold (0: not given) */
    const char *lss;          /* --lss */
    const char *json;         /* --json */
    int quiet, verbose;
    int help;
    int version;            /* --version */
    int plan;               /* --plan: calibrate and predict, simulate nothing to keep;
                             * LSQT_PLAN_CALIBRATION: one of its calibration runs */
    int sampling_given;       /* a flag that fixes the sampling (-wo, -wi, -s, ...) was given */
    int shard_k, shard_n;     /* --shard K/N (shard_n 0: not sharded) */
    int refine;               /* --refine: a shard does only what its state owes */
    int from_below;           /* --from-below: also the slices of light entering from below */
    int wo_given, wi_given, rx_given, rp_given; /* -wo, -wi, -rx, -rp were given */
    int grid_no, grid_ni, grid_nphi; /* --grid NO,NI,NPHI (grid_no 0: no grid; directions.h) */
    int grid_rgl;             /* the grid is --rgl-grid NT,NU: grid_no NT, grid_ni NU, grid_nphi 0 */
    const char *wavelengths;  /* --wavelengths LIST (NULL: none; lsqt/bands.h reads it) */
} lsqt_cli;

/* Returns 0, or 2 with err naming the flag and what it expects. */
int lsqt_cli_parse(int argc, char **argv, lsqt_cli *c, char *err, size_t errcap);

void lsqt_cli_help(FILE *f);

/* Strict number parsing: the whole token must be a finite number. */
int lsqt_parse_double(const char *s, double *out);
/* A count: a finite number with an integral value in [lo, hi] ("1e7" is fine). */
int lsqt_parse_count(const char *s, double lo, double hi, uint64_t *out);
/* An exact unsigned 64-bit integer: decimal digits only, at most 2^64 - 1. */
int lsqt_parse_u64(const char *s, uint64_t *out);

#ifdef __cplusplus
}
#endif
#endif
