/* Private to host/input/: the one table that describes LSQT lines and models (names,
 * keys, defaults, valid ranges; lsqt.c holds it, assembly.c reads it), and a small
 * bounded string builder (strbuf.c).
 * The parser reads input with the table and the canonical writer writes with it, so
 * whatever is written reads back the same. */
#ifndef LSQT_INTERNAL_H
#define LSQT_INTERNAL_H

#include <stddef.h>

#define LSQT_MAX_KEYS 8 /* most keys any line head or model has */

enum lsqt_value_type {
    LSQT_NUM,   /* finite double */
    LSQT_INT,   /* integer, stored in an int */
    LSQT_CHOICE, /* one word of `choices`, stored as its index in an int */
    LSQT_TABLE   /* KEY=@FILE, a phase function's table (lsqt_phase_table), required: stored
                  * as 1 + its index in the assembly's phase_tables (and in lsqt_phase.table) */
};

typedef struct lsqt_key {
    const char *name;
    int type;                   /* enum lsqt_value_type */
    double def;                 /* default; iter_count 0 means "auto" */
    double lo, hi;              /* valid range (LSQT_NUM, LSQT_INT) */
    int lo_open, hi_open;       /* 1 when the bound itself is excluded */
    const char *const *choices; /* LSQT_CHOICE: NULL-terminated words */
    size_t offset;              /* field in the line's struct (lsqt_medium or lsqt_layer) */
    int required;               /* no default: the key must be written */
    int in_double;              /* LSQT_INT, LSQT_CHOICE: stored in a double (a phase's v) */
} lsqt_key;

typedef struct lsqt_model {
    const char *name;  /* seed name, written by the canonical writer */
    const char *alias; /* short name of the later public version; NULL for line heads */
    int kind;          /* enum lsqt_phase_kind / lsqt_bsdf_kind */
    const char *macro; /* kernel build option suffix "PHASE_HG"...; NULL: none needed */
    const lsqt_key *keys;
    int n_keys;
} lsqt_model;

/* A kind of line: its head (Medium, Layer) with its keys, then one of its models. */
typedef struct lsqt_line_desc {
    const lsqt_model *head;
    const lsqt_model *models;
    int n_models;
    const char *model_what; /* "phase model" / "BSDF model", for messages */
    size_t kind_offset;     /* int field of the line's struct that holds the model kind */
} lsqt_line_desc;

extern const lsqt_line_desc lsqt_medium_line; /* fills lsqt_medium */
extern const lsqt_line_desc lsqt_layer_line;  /* fills lsqt_layer */

/* The model of `kind` in a line description; NULL when there is none. */
const lsqt_model *lsqt_model_of_kind(const lsqt_line_desc *d, int kind);

/* Appends like snprintf: `len` counts every byte asked for, `buf` keeps what fits and
 * stays NUL terminated (buf may be NULL when cap is 0). */
typedef struct lsqt_sb {
    char *buf;
    size_t cap, len;
} lsqt_sb;

void lsqt_sb_init(lsqt_sb *sb, char *buf, size_t cap);
void lsqt_sb_printf(lsqt_sb *sb, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
