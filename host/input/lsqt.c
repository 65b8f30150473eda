/* LSQT parser and validator (docs/guide.md, the LSQT language; docs/design.md section 1).
 *
 * The input is read line by line (media and layers alternate), each line with the model
 * table below, which is the only place that names keys, defaults and valid ranges. Then
 * whole-assembly rules run: pruning of what light cannot reach, then the rules about the
 * bottom medium and notes. The input is untrusted (it is fuzzed): it need not be NUL
 * terminated, may hold any bytes, and every failure is a message, never a crash. */
#include "lsqt/assembly.h"
#include "lsqt/bands.h"
#include "lsqt/util.h"
#include "lsqt_internal.h"

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- The model table ------------------------------------------------------------ */

#define OPEN 1
#define CLOSED 0
#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))
#define MED(f) offsetof(lsqt_medium, f)
#define PHASE(f) offsetof(lsqt_medium, phase.f)
#define LAY(f) offsetof(lsqt_layer, f)

#define NUM(name, def, lo, lo_open, hi, hi_open, off) \
    { name, LSQT_NUM, def, lo, hi, lo_open, hi_open, NULL, off, 0, 0 }
#define MODEL(name, alias, kind, macro, keys) { name, alias, kind, macro, keys, COUNT(keys) }

/* Media: upper bounds only keep the numbers sane; eta < 1 is refused later except for
 * the metal below a conductive layer. */
static const lsqt_key medium_keys[] = {
    NUM("eta", 1, 0, OPEN, 100, CLOSED, MED(eta)),
    NUM("mua", 0, 0, CLOSED, 1e12, CLOSED, MED(mua)),
    NUM("mus", 0, 0, CLOSED, 1e12, CLOSED, MED(mus)),
};

/* Layers: |z| is bounded so that thicknesses stay finite. */
static const lsqt_key layer_keys[] = {
    { "z", LSQT_NUM, 0, -1e12, 1e12, CLOSED, CLOSED, NULL, LAY(z), 1, 0 },
};

static const lsqt_model medium_head = MODEL("Medium", NULL, 0, NULL, medium_keys);
static const lsqt_model layer_head = MODEL("Layer", NULL, 0, NULL, layer_keys);

/* The models' keys and tables, expanded from include/lsqt/model_list.h. A key fills its
 * slot of lsqt_phase.v or lsqt_layer.v (a double, integers and choices too). */
#define PHASE_KEY(ID, F, name, type, def, lo, lo_open, hi, hi_open, words) \
    { name, LSQT_##type, def, lo, hi, lo_open, hi_open, words, PHASE(v) + LSQT_##ID##_##F * sizeof(double), \
      LSQT_##type == LSQT_TABLE, 1 },
#define BSDF_KEY(ID, F, name, type, def, lo, lo_open, hi, hi_open, words) \
    { name, LSQT_##type, def, lo, hi, lo_open, hi_open, words, LAY(v) + LSQT_##ID##_##F * sizeof(double), 0, 1 },
#define PHASE_KEYS(ID, ...) static const lsqt_key ID##_phase_keys[] = { LSQT_KEYS_##ID(PHASE_KEY, ID) };
#define BSDF_KEYS(ID, ...) static const lsqt_key ID##_bsdf_keys[] = { LSQT_KEYS_##ID(BSDF_KEY, ID) };
LSQT_PHASES(PHASE_KEYS)
LSQT_BSDFS(BSDF_KEYS)

#define PHASE_MODEL(ID, num, name, alias, ...) MODEL(name, alias, LSQT_PHASE_##ID, "PHASE_" #ID, ID##_phase_keys),
#define BSDF_MODEL(ID, num, name, alias, ...) MODEL(name, alias, LSQT_BSDF_##ID, "BSDF_" #ID, ID##_bsdf_keys),
static const lsqt_model phase_models[] = { LSQT_PHASES(PHASE_MODEL) };
static const lsqt_model bsdf_models[] = {
    { "NullBsdf", "Null", LSQT_BSDF_NULL, NULL, NULL, 0 },
    LSQT_BSDFS(BSDF_MODEL)
};

#define FITS(ID, ...) _Static_assert(LSQT_##ID##_N_KEYS <= LSQT_MAX_MODEL_KEYS, "v[] too small for " #ID);
LSQT_PHASES(FITS)
LSQT_BSDFS(FITS)

const lsqt_line_desc lsqt_medium_line = {
    &medium_head, phase_models, COUNT(phase_models), "phase model", PHASE(kind),
};
const lsqt_line_desc lsqt_layer_line = {
    &layer_head, bsdf_models, COUNT(bsdf_models), "BSDF model", LAY(kind),
};

const lsqt_model *lsqt_model_of_kind(const lsqt_line_desc *d, int kind)
{
    for (int i = 0; i < d->n_models; i++)
        if (d->models[i].kind == kind)
            return &d->models[i];
    return NULL;
}

/* Whether a BSDF takes the medium below it as its complex index eta + i*mua (the model
 * list's BANDS INDEX: a metal, which neither scatters nor is clear), and the name of the
 * first such model, for messages. */
static int index_below(int kind)
{
#define INDEX_BELOW(ID, num, name, alias, prefix, sampler, mirror, transmits, bands, ...) \
    LSQT_IF_INDEX_##bands(|| kind == LSQT_BSDF_##ID)
    return 0 LSQT_BSDFS(INDEX_BELOW);
#undef INDEX_BELOW
}

static const char *index_below_name(void)
{
    for (size_t i = 0; i < COUNT(bsdf_models); i++)
        if (index_below(bsdf_models[i].kind)) return bsdf_models[i].name;
    return "a metal's BSDF";
}

/* ---- Tokens ---------------------------------------------------------------------- */

typedef struct span {
    const char *p;
    size_t n;
} span;

static int span_is(span s, const char *word)
{
    size_t n = strlen(word);
    return s.p && s.n == n && memcmp(s.p, word, n) == 0;
}

static span word(const char *s)
{
    span w = { s, strlen(s) };
    return w;
}

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

/* Next whitespace-separated token in [*cur, end); 0 at the end. */
static int next_token(const char **cur, const char *end, span *tok)
{
    const char *p = *cur;
    while (p < end && is_space(*p))
        p++;
    if (p == end)
        return 0;
    tok->p = p;
    while (p < end && !is_space(*p))
        p++;
    tok->n = (size_t)(p - tok->p);
    *cur = p;
    return 1;
}

/* A token for a message: at most 40 bytes, anything unprintable shown as '?'. */
static const char *show(span s, char out[48])
{
    size_t n = s.n > 40 ? 40 : s.n, i;
    for (i = 0; i < n; i++)
        out[i] = (s.p[i] >= 0x20 && s.p[i] < 0x7f) ? s.p[i] : '?';
    strcpy(out + i, s.n > n ? "..." : "");
    return out;
}

/* ---- Parser state and diagnostics --------------------------------------------------- */

typedef struct medium_rec {
    lsqt_medium m;
    span tok[LSQT_MAX_KEYS]; /* its Medium keys as written (p NULL: default), for messages */
} medium_rec;

typedef struct parser {
    const char *name;
    lsqt_diag *diag;
    int line;
    const char *line_end; /* the end of the line being read (before any comment) */
    medium_rec *media;
    int n_media, cap_media;
    lsqt_layer *layers;
    int n_layers, cap_layers;
    int n_pruned;
    lsqt_bands *bands; /* NULL: one band, numbers only */
    int band;          /* the band whose values are read */
    /* A run with bands parses every band twice (lsqt_parse): first a survey (no
     * pruning, no rule on the bottom medium) that finds what every band shares, then each
     * band with the shared decisions. */
    int survey;
    int prune_at;                   /* >= 0: prune below this layer (the first opaque in every band) */
    const unsigned char *keep_phase; /* per medium: 1 when it scatters in some band, so its phase
                                      * model stays where its mus is 0 */
    lsqt_phase_table *ptabs;        /* the phase tables read (TABLE keys), for the assembly */
    int n_ptabs;
} parser;

/* One line being read. */
typedef struct line_state {
    const lsqt_line_desc *desc;
    unsigned char *base;     /* the lsqt_medium or lsqt_layer being filled */
    const lsqt_model *model; /* phase/BSDF model; NULL until its name is read */
    span head, last;         /* "Medium"/"Layer" token, last token read */
    span head_tok[LSQT_MAX_KEYS];
    span model_tok[LSQT_MAX_KEYS];
} line_state;

/* Records the first error as "NAME:LINE: error: WHAT at 'TOKEN'; expected ..." and
 * returns 2. line 0: not line specific; tok NULL: no token to show. */
static int fail(parser *P, int line, const span *tok, const char *what, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;
static int fail(parser *P, int line, const span *tok, const char *what, const char *fmt, ...)
{
    lsqt_diag *d = P->diag;
    if (d->error[0])
        return 2;
    lsqt_sb sb;
    lsqt_sb_init(&sb, d->error, sizeof d->error);
    lsqt_sb_printf(&sb, "%s", P->name);
    if (line > 0)
        lsqt_sb_printf(&sb, ":%d", line);
    lsqt_sb_printf(&sb, ": error: ");
    if (P->bands && P->bands->n > 1) {
        lsqt_sb_printf(&sb, "band %d", P->band + 1);
        if (P->bands->wl)
            lsqt_sb_printf(&sb, " (%g nm)", P->bands->wl[P->band]);
        lsqt_sb_printf(&sb, ": ");
    }
    lsqt_sb_printf(&sb, "%s", what);
    if (tok) {
        char shown[48];
        lsqt_sb_printf(&sb, " at '%s'", show(*tok, shown));
    }
    char expected[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(expected, sizeof expected, fmt, ap);
    va_end(ap);
    lsqt_sb_printf(&sb, "; expected %s", expected);
    d->error_line = line;
    return 2;
}

static void note(parser *P, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void note(parser *P, int line, const char *fmt, ...)
{
    lsqt_diag *d = P->diag;
    if (d->n_notes >= LSQT_DIAG_MAX_NOTES)
        return;
    char text[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    lsqt_sb sb;
    lsqt_sb_init(&sb, d->notes[d->n_notes++], sizeof d->notes[0]);
    lsqt_sb_printf(&sb, "%s:%d: note: %s", P->name, line, text);
}

static int out_of_memory(parser *P) { return fail(P, 0, NULL, "out of memory", "less input"); }

/* Room for one more element of `size` bytes in arr (n used, *cap allocated): returns
 * the array, perhaps moved, or NULL (arr is then still valid). */
static void *grow(void *arr, int *cap, int n, size_t size)
{
    if (n < *cap)
        return arr;
    if (*cap > INT_MAX / 2)
        return NULL;
    int new_cap = *cap ? 2 * *cap : 8;
    void *p = realloc(arr, (size_t)new_cap * size);
    if (p)
        *cap = new_cap;
    return p;
}

/* ---- Table look-ups and messages built from the table ------------------------------- */

static const lsqt_model *find_model(const lsqt_line_desc *d, span word)
{
    for (int i = 0; i < d->n_models; i++)
        if (span_is(word, d->models[i].name) || span_is(word, d->models[i].alias))
            return &d->models[i];
    return NULL;
}

static const lsqt_key *find_key(const lsqt_model *m, span name)
{
    for (int i = 0; i < m->n_keys; i++)
        if (span_is(name, m->keys[i].name))
            return &m->keys[i];
    return NULL;
}

/* The first head or model of any line that has a key of this name. */
static const lsqt_model *key_owner(span name)
{
    const lsqt_line_desc *descs[] = { &lsqt_medium_line, &lsqt_layer_line };
    for (int d = 0; d < 2; d++) {
        if (find_key(descs[d]->head, name))
            return descs[d]->head;
        for (int i = 0; i < descs[d]->n_models; i++)
            if (find_key(&descs[d]->models[i], name))
                return &descs[d]->models[i];
    }
    return NULL;
}

static const lsqt_model *current_model(const line_state *ls)
{
    return ls->model ? ls->model : ls->desc->head;
}

static span *given_tokens(line_state *ls) { return ls->model ? ls->model_tok : ls->head_tok; }

/* The token a key was written as, or NULL when it took its default. */
static const span *token_of(const span *toks, const lsqt_model *m, const char *key)
{
    for (int i = 0; i < m->n_keys; i++)
        if (strcmp(m->keys[i].name, key) == 0)
            return toks[i].p ? &toks[i] : NULL;
    return NULL;
}

static void list_models(const lsqt_line_desc *d, lsqt_sb *sb)
{
    for (int i = 0; i < d->n_models; i++)
        lsqt_sb_printf(sb, "%s%s", i ? ", " : "", d->models[i].name);
}

/* "; did you mean 'X'?" after SB when TOK is close to a key of the line's model or (with
 * models) to a model name (a slip of the keyboard, not a misunderstanding). */
static void did_you_mean(const line_state *ls, span tok, int models, lsqt_sb *sb)
{
    const lsqt_model *m = current_model(ls);
    const char *names[64];
    int n = 0;
    for (int i = 0; i < m->n_keys && n < 64; i++) names[n++] = m->keys[i].name;
    for (int i = 0; models && i < ls->desc->n_models && n < 63; i++) {
        names[n++] = ls->desc->models[i].name;
        if (ls->desc->models[i].alias) names[n++] = ls->desc->models[i].alias;
    }
    const char *near = lsqt_closest(tok.p, tok.n, names, n);
    if (near) lsqt_sb_printf(sb, "; did you mean '%s'?", near);
}

/* What may come next on the line: "one of: eta mua mus or a phase model (...)". */
static void expected_words(const line_state *ls, lsqt_sb *sb)
{
    const lsqt_model *m = current_model(ls);
    if (m->n_keys == 0) {
        lsqt_sb_printf(sb, "nothing after %s (it has no keys)", m->name);
        return;
    }
    lsqt_sb_printf(sb, "one of:");
    for (int i = 0; i < m->n_keys; i++)
        lsqt_sb_printf(sb, " %s", m->keys[i].name);
    if (ls->model) {
        lsqt_sb_printf(sb, " (keys of %s)", m->name);
    } else {
        lsqt_sb_printf(sb, " or a %s (", ls->desc->model_what);
        list_models(ls->desc, sb);
        lsqt_sb_printf(sb, ")");
    }
}

static void describe_range(const lsqt_key *k, lsqt_sb *sb)
{
    lsqt_sb_printf(sb, " in %c%g, %g%c", k->lo_open ? '(' : '[', k->lo, k->hi,
                   k->hi_open ? ')' : ']');
    if (k->hi == LSQT_G_MAX)
        lsqt_sb_printf(sb, " (closer to +-1 the forward peak (1+|g|)/(4 pi (1-|g|)^2) would outgrow the "
                           "tallies' range)");
}

/* What a valid value of the key looks like: "g=<number> in (-1, 1)". */
static void describe_value(const lsqt_key *k, lsqt_sb *sb)
{
    if (k->type == LSQT_CHOICE) {
        lsqt_sb_printf(sb, "%s=", k->name);
        for (int i = 0; k->choices[i]; i++)
            lsqt_sb_printf(sb, "%s%s", i ? "|" : "", k->choices[i]);
        return;
    }
    if (k->type == LSQT_TABLE) {
        lsqt_sb_printf(sb, "%s=@FILE, a phase table (rows of cos theta and its value, covering [-1, 1]; the same in "
                       "every band)", k->name);
        return;
    }
    lsqt_sb_printf(sb, "%s=<%s>", k->name, k->type == LSQT_INT ? "integer" : "number");
    describe_range(k, sb);
}

/* ---- Values -------------------------------------------------------------------------- */

static int is_digit(char c) { return c >= '0' && c <= '9'; }

static size_t skip_digits(span s, size_t i)
{
    while (i < s.n && is_digit(s.p[i]))
        i++;
    return i;
}

/* [+-] digits [. digits] [e [+-] digits], with at least one mantissa digit. Checked
 * here because strtod also takes "inf", "nan" and hex floats. */
static int is_decimal(span s)
{
    size_t i = 0;
    if (i < s.n && (s.p[i] == '+' || s.p[i] == '-'))
        i++;
    size_t int_end = skip_digits(s, i), frac_end = int_end;
    if (int_end < s.n && s.p[int_end] == '.')
        frac_end = skip_digits(s, int_end + 1);
    if (int_end == i && frac_end <= int_end + 1)
        return 0;
    i = frac_end;
    if (i < s.n && (s.p[i] == 'e' || s.p[i] == 'E')) {
        i++;
        if (i < s.n && (s.p[i] == '+' || s.p[i] == '-'))
            i++;
        size_t exp_start = i;
        i = skip_digits(s, i);
        if (i == exp_start)
            return 0;
    }
    return i == s.n;
}

/* Strict number: the whole token a finite decimal. The '.' reaches strtod as the
 * locale's decimal point, so a caller's setlocale cannot change what parses. Returns
 * NULL or why the token is not a number. */
static const char *parse_number(span s, double *v)
{
    if (!is_decimal(s))
        return "not a number";
    char buf[160];
    const char *point = localeconv()->decimal_point;
    size_t point_len = strlen(point), o = 0;
    if (s.n + point_len >= sizeof buf) /* one point at most, by the grammar */
        return "number too long";
    for (size_t i = 0; i < s.n; i++) {
        if (s.p[i] == '.') {
            memcpy(buf + o, point, point_len);
            o += point_len;
        } else {
            buf[o++] = s.p[i];
        }
    }
    buf[o] = '\0';
    char *end;
    errno = 0;
    *v = strtod(buf, &end);
    if (end != buf + o)
        return "not a number";
    if (!isfinite(*v))
        return "number out of range";
    /* ERANGE with a result below DBL_MIN: the text is not 0, but it would be read as 0
     * (or a subnormal that loses digits). */
    if (errno == ERANGE && fabs(*v) < DBL_MIN)
        return "number too small (below 2.2e-308 it cannot be held; write 0 for zero)";
    return NULL;
}

static const char *check_range(const lsqt_key *k, double v)
{
    if (k->lo_open ? !(v > k->lo) : !(v >= k->lo))
        return "value out of range";
    if (k->hi_open ? !(v < k->hi) : !(v <= k->hi))
        return "value out of range";
    return NULL;
}

/* Returns NULL or why the text is not a valid value of the key. */
static const char *parse_value(const lsqt_key *k, span text, double *v)
{
    if (text.n == 0)
        return "missing value after '='";
    if (k->type == LSQT_CHOICE) {
        for (int i = 0; k->choices[i]; i++) {
            if (span_is(text, k->choices[i])) {
                *v = i;
                return NULL;
            }
        }
        return "unknown value";
    }
    const char *why = parse_number(text, v);
    if (!why && k->type == LSQT_INT && *v != floor(*v))
        why = "not an integer";
    return why ? why : check_range(k, *v);
}

static void store(unsigned char *base, const lsqt_key *k, double v)
{
    if (k->type == LSQT_NUM || k->in_double)
        *(double *)(void *)(base + k->offset) = v;
    else
        *(int *)(void *)(base + k->offset) = (int)v;
}

static void apply_defaults(const lsqt_model *m, unsigned char *base)
{
    for (int i = 0; i < m->n_keys; i++)
        store(base, &m->keys[i], m->keys[i].def);
}

/* ---- Values per band ------------------------------------------------------------------ */

/* The table of @FILE (path relative to the bands' folder), read once; NULL after a
 * failure recorded with fail(). */
static const lsqt_band_table *band_table(parser *P, span tok, span file)
{
    lsqt_bands *b = P->bands;
    char path[LSQT_PATH_CAP], err[512];
    if (file.n == 0)
        return fail(P, P->line, &tok, "an empty table path", "a file name after '@': KEY=@FILE"), NULL;
    int n = snprintf(path, sizeof path, "%s%s%.*s", file.n && file.p[0] != '/' && b->dir ? b->dir : "",
                     file.n && file.p[0] != '/' && b->dir ? "/" : "", (int)file.n, file.p);
    if (n < 0 || (size_t)n >= sizeof path) {
        fail(P, P->line, &tok, "table path too long", "a path of fewer than %d bytes", LSQT_PATH_CAP);
        return NULL;
    }
    for (int i = 0; i < b->n_tables; i++)
        if (strcmp(b->table_paths[i], path) == 0)
            return &b->tables[i];
    size_t len = 0;
    char *text = lsqt_read_text(path, LSQT_INPUT_MAX, &len, err, sizeof err);
    lsqt_band_table t;
    if (!text || lsqt_band_table_parse(text, len, path, &t, err, sizeof err)) {
        /* a path with a space reads as the path's start and a word after it */
        const char *q = tok.p + tok.n, *end = P->line_end ? P->line_end : q;
        while (q < end && (*q == ' ' || *q == '\t')) q++;
        const char *w = q;
        while (q < end && *q != ' ' && *q != '\t' && *q != '=') q++;
        const int spaced = !text && w > tok.p + tok.n && w < end && (q == end || *q != '=');
        free(text);
        fail(P, P->line, &tok, "unreadable table", "a table of wavelength (nm) and value rows: %s%s", err,
             spaced ? " (a token ends at a space: a table's path cannot contain spaces; rename the file or link it "
                      "under a name without them)" : "");
        return NULL;
    }
    free(text);
    char **paths = realloc(b->table_paths, (size_t)(b->n_tables + 1) * sizeof *paths);
    if (paths)
        b->table_paths = paths;
    lsqt_band_table *tables = paths ? realloc(b->tables, (size_t)(b->n_tables + 1) * sizeof *tables) : NULL;
    if (tables)
        b->tables = tables;
    char *copy = tables ? malloc(strlen(path) + 1) : NULL;
    if (!copy) {
        lsqt_band_table_free(&t);
        out_of_memory(P);
        return NULL;
    }
    strcpy(copy, path);
    b->table_paths[b->n_tables] = copy, b->tables[b->n_tables] = t;
    return &b->tables[b->n_tables++];
}

/* v with the fewest digits that read back as v ("699.9999", not "700"), into buf[32]. */
static const char *shortest(double v, char *buf)
{
    for (int prec = 6; prec <= 17; prec++) {
        snprintf(buf, 32, "%.*g", prec, v);
        if (strtod(buf, NULL) == v) break;
    }
    return buf;
}

/* A number key written as a list or @FILE: its value in band P->band into *v (range
 * checked). Returns 0, or 2 after fail(). text is the value after '='. */
static int band_value(parser *P, const lsqt_key *k, span tok, span text, double *v)
{
    char buf[640];
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, sizeof buf);
    const int nb = P->bands ? P->bands->n : 1;
    if (strcmp(k->name, "z") == 0)
        return fail(P, P->line, &tok, "z as a value per band", "one number: z is geometry, the same in every band");
    const char *why;
    if (text.p[0] == '@') {
        if (k->type != LSQT_NUM)
            return fail(P, P->line, &tok, "a table for a whole number", "a number or a comma list of whole numbers");
        if (!P->bands || !P->bands->wl)
            return fail(P, P->line, &tok, "a table without wavelengths",
                        "a number or a comma list (KEY=@FILE is a spectral table, wavelength and value, and needs "
                        "--wavelengths: the table is read at them; a phase function's table of cos theta is "
                        "a key of a tabulated model, such as table=@FILE)");
        span file = { text.p + 1, text.n - 1 };
        const lsqt_band_table *t = band_table(P, tok, file);
        if (!t)
            return 2;
        double wl = P->bands->wl[P->band];
        if (lsqt_band_table_at(t, wl, v)) {
            char a[32], lo[32], hi[32];
            return fail(P, P->line, &tok, "wavelength outside the table", "a table that covers %s nm (it covers %s to "
                        "%s nm%s)", shortest(wl, a), shortest(t->wl[0], lo), shortest(t->wl[t->n - 1], hi),
                        t->wl[t->n - 1] < 10 && wl >= 100
                            ? "; its wavelengths look like um: a table's wavelengths are in nm, um x 1000" : "");
        }
        why = check_range(k, *v);
    } else {
        int count = 1;
        for (size_t i = 0; i < text.n; i++)
            count += text.p[i] == ',';
        if (count > LSQT_MAX_BANDS)
            return fail(P, P->line, &tok, "too many values in a list",
                        "at most %d comma-separated values, one per band (this list has %d): a run has at most "
                        "%d bands", LSQT_MAX_BANDS, count, LSQT_MAX_BANDS);
        if (nb == 0) { /* no --wavelengths: the first list sets the band count */
            P->bands->n = count, P->bands->count_line = P->line;
        } else if (nb == 1)
            return fail(P, P->line, &tok, "a list of values in a run of one band",
                        "one number, with '.' as its decimal point (a comma list gives one value per band: "
                        "a run with bands, such as --wavelengths, reads it)");
        if (count != P->bands->n) {
            describe_value(k, &sb);
            if (P->bands->count_line)
                return fail(P, P->line, &tok, "lists of different lengths",
                            "%d comma-separated values, as the list on line %d (this list has %d), or one number: %s",
                            P->bands->n, P->bands->count_line, count, buf);
            return fail(P, P->line, &tok, "wrong number of values",
                        "%d comma-separated values, one per band of --wavelengths (this list has %d), or one "
                        "number: %s", P->bands->n, count, buf);
        }
        const char *p = text.p, *end = text.p + text.n;
        for (int i = 0; i < P->band; i++)
            p = (const char *)memchr(p, ',', (size_t)(end - p)) + 1;
        const char *e = memchr(p, ',', (size_t)(end - p));
        span one = { p, (size_t)((e ? e : end) - p) };
        why = one.n ? parse_value(k, one, v) : "empty value in the list";
    }
    if (why) {
        describe_value(k, &sb);
        return fail(P, P->line, &tok, why, "%s", buf);
    }
    return 0;
}

/* A TABLE key's value, table=@FILE: the phase table read (path relative to the bands'
 * folder, as KEY=@FILE), kept for the assembly; *v its number (1-based). One table in
 * every band: a list of them is refused. Returns 0, or 2 after fail(). */
static int phase_table(parser *P, const lsqt_key *k, span tok, span text, double *v)
{
    char buf[400], path[LSQT_PATH_CAP], err[512];
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, sizeof buf);
    describe_value(k, &sb);
    if (text.n && memchr(text.p, ',', text.n))
        return fail(P, P->line, &tok, "a list of phase tables", "one table, %s: a phase table is the same in every "
                    "band (a table per band is not supported)", buf);
    if (text.n < 2 || text.p[0] != '@')
        return fail(P, P->line, &tok, text.n && text.p[0] == '@' ? "an empty table path" : "not a table", "%s", buf);
    const char *dir = P->bands ? P->bands->dir : NULL;
    int n = snprintf(path, sizeof path, "%s%s%.*s", text.p[1] != '/' && dir ? dir : "", text.p[1] != '/' && dir ? "/" : "",
                     (int)text.n - 1, text.p + 1);
    if (n < 0 || (size_t)n >= sizeof path)
        return fail(P, P->line, &tok, "table path too long", "a path of fewer than %d bytes", LSQT_PATH_CAP);
    size_t len = 0;
    char *t_text = lsqt_read_text(path, LSQT_INPUT_MAX, &len, err, sizeof err);
    lsqt_phase_table t;
    if (!t_text || lsqt_phase_table_parse(t_text, len, path, &t, err, sizeof err)) {
        free(t_text);
        return fail(P, P->line, &tok, "unreadable phase table", "%s: %s", buf, err);
    }
    free(t_text);
    t.path = strdup(path);
    lsqt_phase_table *all = t.path ? realloc(P->ptabs, (size_t)(P->n_ptabs + 1) * sizeof *all) : NULL;
    if (!all) {
        lsqt_phase_table_free(&t);
        return out_of_memory(P);
    }
    P->ptabs = all;
    P->ptabs[P->n_ptabs++] = t;
    *v = P->n_ptabs;
    return 0;
}

/* ---- One line ------------------------------------------------------------------------ */

static int read_key(parser *P, line_state *ls, span tok, const char *eq)
{
    const lsqt_model *m = current_model(ls);
    span name = { tok.p, (size_t)(eq - tok.p) };
    span text = { eq + 1, tok.n - name.n - 1 };
    char buf[640], shown[48];
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, sizeof buf);

    const lsqt_key *k = find_key(m, name);
    if (!k) {
        expected_words(ls, &sb);
        const lsqt_model *owner = name.n ? key_owner(name) : NULL;
        if (owner)
            lsqt_sb_printf(&sb, " ('%s' is a key of %s)", show(name, shown), owner->name);
        else
            did_you_mean(ls, name, 0, &sb);
        return fail(P, P->line, &tok, name.n ? "unknown key" : "missing key name before '='",
                    "%s", buf);
    }
    span *given = &given_tokens(ls)[k - m->keys];
    if (given->p)
        return fail(P, P->line, &tok, "repeated key", "%s at most once (already given as '%s')",
                    k->name, show(*given, shown));
    double v = 0;
    if (k->type == LSQT_TABLE) {
        if (ls->desc != &lsqt_medium_line)
            return fail(P, P->line, &tok, "a table key of a BSDF", "a phase function's table (BSDFs have none yet)");
        if (phase_table(P, k, tok, text, &v))
            return 2;
        ((lsqt_medium *)(void *)ls->base)->phase.table = (int)v;
    } else if (k->type != LSQT_CHOICE && text.n && (text.p[0] == '@' || memchr(text.p, ',', text.n))) {
        if (band_value(P, k, tok, text, &v))
            return 2;
    } else {
        const char *why = parse_value(k, text, &v);
        if (why) {
            describe_value(k, &sb);
            return fail(P, P->line, &tok, why, "%s", buf);
        }
    }
    store(ls->base, k, v);
    *given = tok;
    return 0;
}

/* A word without '=': the model name, or a mistake. */
static int read_word(parser *P, line_state *ls, span tok)
{
    const lsqt_model *model = find_model(ls->desc, tok);
    if (model && !ls->model) {
        ls->model = model;
        *(int *)(void *)(ls->base + ls->desc->kind_offset) = model->kind;
        apply_defaults(model, ls->base);
        return 0;
    }
    char buf[640], what[96];
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, sizeof buf);
    const lsqt_key *k = find_key(current_model(ls), tok);
    if (k) {
        describe_value(k, &sb);
        return fail(P, P->line, &tok, "missing '=' and value", "%s", buf);
    }
    if (model)
        snprintf(what, sizeof what, "a second %s", ls->desc->model_what);
    else
        snprintf(what, sizeof what, "unknown word");
    expected_words(ls, &sb);
    if (!model) did_you_mean(ls, tok, !ls->model, &sb);
    return fail(P, P->line, &tok, what, "%s", buf);
}

/* Names, keys and numbers are printable ASCII; anything else is garbage. */
static int check_chars(parser *P, span tok)
{
    for (size_t i = 0; i < tok.n; i++) {
        unsigned char c = (unsigned char)tok.p[i];
        if (c <= 0x20 || c >= 0x7f)
            return fail(P, P->line, &tok, "invalid character", "printable ASCII (byte 0x%02x "
                        "at offset %zu of the word is not)", c, i);
    }
    return 0;
}

static int wrong_head(parser *P, const line_state *ls)
{
    const char *want = ls->desc->head->name;
    const char *other = ls->desc == &lsqt_medium_line ? lsqt_layer_line.head->name
                                                      : lsqt_medium_line.head->name;
    char what[64];
    if (span_is(ls->head, other))
        snprintf(what, sizeof what, "a %s line where a %s line belongs", other, want);
    else
        snprintf(what, sizeof what, "unknown line name");
    return fail(P, P->line, &ls->head, what,
                "%s here (lines alternate Medium, Layer, Medium, ..., Medium)", want);
}

static int check_required(parser *P, const line_state *ls)
{
    const lsqt_model *h = ls->desc->head;
    for (int i = 0; i < h->n_keys; i++) {
        if (h->keys[i].required && !ls->head_tok[i].p) {
            char what[64], buf[128];
            lsqt_sb sb;
            lsqt_sb_init(&sb, buf, sizeof buf);
            describe_value(&h->keys[i], &sb);
            snprintf(what, sizeof what, "missing required key %s", h->keys[i].name);
            return fail(P, P->line, &ls->head, what, "%s right after %s", buf, h->name);
        }
    }
    const lsqt_model *m = ls->model;
    for (int i = 0; m && i < m->n_keys; i++) {
        if (m->keys[i].required && !ls->model_tok[i].p) {
            char what[64], buf[256];
            lsqt_sb sb;
            lsqt_sb_init(&sb, buf, sizeof buf);
            describe_value(&m->keys[i], &sb);
            snprintf(what, sizeof what, "missing required key %s", m->keys[i].name);
            return fail(P, P->line, &ls->head, what, "%s after %s", buf, m->name);
        }
    }
    return 0;
}

static int auto_iter_count(double alpha)
{
    return alpha <= 0.1 ? 1 : alpha <= 0.2 ? 2 : alpha <= 0.5 ? 4 : 6;
}

/* Top and bottom media must be clear (the metal below a conductive layer excepted). */
static int require_clear(parser *P, const medium_rec *r, const char *which)
{
    static const char *const keys[] = { "mua", "mus" };
    const double values[] = { r->m.mua, r->m.mus };
    for (int i = 0; i < 2; i++) {
        if (values[i] > 0) {
            char what[64];
            snprintf(what, sizeof what, "the %s medium %s", which, i ? "scatters" : "absorbs");
            return fail(P, r->m.line, token_of(r->tok, &medium_head, keys[i]), what,
                        "%s=0 (the top and bottom media must neither absorb nor scatter, "
                        "except the metal below a MicrosurfaceConductiveBrdf)", keys[i]);
        }
    }
    return 0;
}

static int finish_medium(parser *P, line_state *ls, lsqt_medium *m)
{
    medium_rec r;
    memset(&r, 0, sizeof r);
    memcpy(r.tok, ls->head_tok, sizeof r.tok);
    const lsqt_layer *above = P->n_layers ? &P->layers[P->n_layers - 1] : NULL;
    const span *eta_tok = token_of(r.tok, &medium_head, "eta");
    const span *mus_tok = token_of(r.tok, &medium_head, "mus");
    char buf[256];
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, sizeof buf);

    if (above && index_below(above->kind)) {
        if (m->mus > 0) {
            char what[96];
            snprintf(what, sizeof what, "the metal below a %s scatters",
                     lsqt_model_of_kind(&lsqt_layer_line, above->kind)->name);
            return fail(P, P->line, mus_tok, what, "mus=0 (the metal's eta + i*mua is the complex index)");
        }
    } else if (m->eta < 1) {
        return fail(P, P->line, eta_tok, "eta below 1", "eta >= 1 (eta < 1 is allowed only for the metal below a %s)",
                    index_below_name());
    }
    if (m->mus > 0 && m->phase.kind == LSQT_PHASE_NONE) {
        list_models(&lsqt_medium_line, &sb);
        return fail(P, P->line, mus_tok, "scattering medium without a phase model",
                    "a phase model after the Medium keys when mus > 0: one of %s", buf);
    }
    if (m->mus == 0 && ls->model && !(P->keep_phase && P->keep_phase[P->n_media])) {
        note(P, P->line, "%s ignored: mus=0, the medium does not scatter", ls->model->name);
        memset(&m->phase, 0, sizeof m->phase);
    }
    m->line = P->line;
    r.m = *m;
    if (P->n_media == 0 && require_clear(P, &r, "top"))
        return 2;
    medium_rec *media = grow(P->media, &P->cap_media, P->n_media, sizeof *P->media);
    if (!media)
        return out_of_memory(P);
    P->media = media;
    P->media[P->n_media++] = r;
    return 0;
}

/* The value of the model's key `name` in the layer, NULL when the model has no such key. */
static double *layer_key(lsqt_layer *l, const lsqt_model *m, const char *name)
{
    const lsqt_key *k = find_key(m, word(name));
    return k ? (double *)(void *)((unsigned char *)l + k->offset) : NULL;
}

static int finish_layer(parser *P, line_state *ls, lsqt_layer *l)
{
    char buf[256];
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, sizeof buf);
    if (!ls->model) {
        list_models(&lsqt_layer_line, &sb);
        return fail(P, P->line, &ls->last, "missing BSDF model",
                    "a BSDF model after the Layer keys: one of %s", buf);
    }
    const lsqt_layer *prev = P->n_layers ? &P->layers[P->n_layers - 1] : NULL;
    if (prev && !(l->z < prev->z))
        return fail(P, P->line, token_of(ls->head_tok, &layer_head, "z"),
                    "layer not below the previous one",
                    "z < %g (z of the layer on line %d; z decreases down the file)", prev->z,
                    prev->line);
    const double *fR = layer_key(l, ls->model, "fR"), *fT = layer_key(l, ls->model, "fT");
    if (fR && fT && *fR + *fT > 1 + 1e-12) {
        /* name whichever of fR, fT was written last */
        const span *fr = token_of(ls->model_tok, ls->model, "fR");
        const span *ft = token_of(ls->model_tok, ls->model, "fT");
        const span *tok = (!ft || (fr && fr->p > ft->p)) ? fr : ft;
        snprintf(buf, sizeof buf, "fR + fT = %g exceeds 1", *fR + *fT);
        return fail(P, P->line, tok, buf, "fR + fT <= 1 (fR=%g, fT=%g; the rest is absorbed)", *fR, *fT);
    }
    /* a microsurface's walks: iter_count 0 is auto, from alpha */
    double *iter = layer_key(l, ls->model, "iter_count");
    const double *ms = layer_key(l, ls->model, "use_multiple_scattering");
    if (iter && *iter == 0)
        *iter = auto_iter_count(*layer_key(l, ls->model, "alpha"));
    l->iter_count = iter ? (int)*iter : 0;
    l->multiple_scattering = ms ? (int)*ms : 0;
    l->line = P->line;
    lsqt_layer *layers = grow(P->layers, &P->cap_layers, P->n_layers, sizeof *P->layers);
    if (!layers)
        return out_of_memory(P);
    P->layers = layers;
    P->layers[P->n_layers++] = *l;
    return 0;
}

/* Reads one non-blank line whose first token is `head`; the rest is [cur, end). */
static int read_line(parser *P, const char *cur, const char *end, span head)
{
    union {
        lsqt_medium m;
        lsqt_layer l;
    } obj;
    line_state ls;
    memset(&obj, 0, sizeof obj);
    memset(&ls, 0, sizeof ls);
    int medium = P->n_media == P->n_layers;
    ls.desc = medium ? &lsqt_medium_line : &lsqt_layer_line;
    ls.base = (unsigned char *)&obj;
    ls.head = ls.last = head;
    if (check_chars(P, head))
        return 2;
    if (!span_is(head, ls.desc->head->name))
        return wrong_head(P, &ls);
    apply_defaults(ls.desc->head, ls.base);

    span tok;
    while (next_token(&cur, end, &tok)) {
        ls.last = tok;
        const char *eq = memchr(tok.p, '=', tok.n);
        if (check_chars(P, tok) || (eq ? read_key(P, &ls, tok, eq) : read_word(P, &ls, tok)))
            return 2;
    }
    if (check_required(P, &ls))
        return 2;
    return medium ? finish_medium(P, &ls, &obj.m) : finish_layer(P, &ls, &obj.l);
}

/* ---- The whole assembly ------------------------------------------------------------ */

/* Light cannot pass the first layer that transmits nothing: keep that layer and, below
 * it, the metal of a conductive layer or else a vacuum; drop the rest. */
static void prune(parser *P)
{
    int p = 0;
    while (p < P->n_layers && lsqt_layer_transmits(&P->layers[p]))
        p++;
    if (P->prune_at >= 0) /* bands: where every band is stopped, not this one */
        p = P->prune_at < P->n_layers ? P->prune_at : P->n_layers;
    if (p == P->n_layers)
        return;
    const lsqt_layer *stop = &P->layers[p];
    const char *name = lsqt_model_of_kind(&lsqt_layer_line, stop->kind)->name; /* a parsed kind: always there */
    medium_rec *below = &P->media[p + 1];
    int last_line = P->media[P->n_media - 1].m.line;
    int metal = index_below(stop->kind);
    /* the metal stays, so pruning starts at the next layer */
    int first_line = metal && p + 1 < P->n_layers ? P->layers[p + 1].line : below->m.line;
    P->n_pruned = P->n_layers - (p + 1);
    P->n_layers = p + 1;
    P->n_media = p + 2;
    if (metal) {
        if (P->n_pruned)
            note(P, stop->line, "%s transmits nothing: lines %d-%d cannot be reached and are "
                 "not modelled (%d layer%s pruned; the metal on line %d is kept)", name,
                 first_line, last_line, P->n_pruned, P->n_pruned > 1 ? "s" : "", below->m.line);
        return;
    }
    const lsqt_medium *m = &below->m;
    int vacuum = m->eta == 1 && m->mua == 0 && m->mus == 0;
    if (P->n_pruned)
        note(P, stop->line, "%s transmits nothing: lines %d-%d cannot be reached and are not "
             "modelled (%d layer%s pruned; the bottom medium is now vacuum)", name, first_line,
             last_line, P->n_pruned, P->n_pruned > 1 ? "s" : "");
    else if (!vacuum)
        note(P, stop->line, "%s transmits nothing: the medium on line %d cannot be reached "
             "and is modelled as vacuum", name, m->line);
    int line = m->line;
    memset(below, 0, sizeof *below);
    below->m.eta = 1;
    below->m.line = line;
}

static void note_null_layers(parser *P)
{
    for (int i = 0; i < P->n_layers; i++) {
        double above = P->media[i].m.eta, below = P->media[i + 1].m.eta;
        if (P->layers[i].kind == LSQT_BSDF_NULL && above != below)
            note(P, P->layers[i].line, "NullBsdf between eta=%g and eta=%g: light passes "
                 "straight on, without refraction", above, below);
    }
}

static int finish_assembly(parser *P)
{
    if (P->n_media == 0)
        return fail(P, 0, NULL, "no layers (the input has no Medium or Layer lines)",
                    "Medium, Layer, Medium, ..., Medium lines with at least one Layer");
    if (P->n_layers == 0)
        return fail(P, P->media[0].m.line, NULL, "no layers",
                    "a Layer line after the Medium on line %d, then a bottom Medium line",
                    P->media[0].m.line);
    if (P->n_media == P->n_layers)
        return fail(P, P->layers[P->n_layers - 1].line, NULL, "the input ends with a layer",
                    "a bottom Medium line after the Layer on line %d",
                    P->layers[P->n_layers - 1].line);
    if (P->survey)
        return 0;
    prune(P);
    if (!index_below(P->layers[P->n_layers - 1].kind) &&
        require_clear(P, &P->media[P->n_media - 1], "bottom"))
        return 2;
    note_null_layers(P);
    return 0;
}

static int hand_over(parser *P, lsqt_assembly *out)
{
    out->layers = malloc((size_t)P->n_layers * sizeof *out->layers);
    out->media = malloc((size_t)P->n_media * sizeof *out->media);
    if (!out->layers || !out->media) {
        lsqt_assembly_free(out);
        return out_of_memory(P);
    }
    memcpy(out->layers, P->layers, (size_t)P->n_layers * sizeof *out->layers);
    for (int i = 0; i < P->n_media; i++)
        out->media[i] = P->media[i].m;
    out->n_layers = P->n_layers;
    out->n_pruned_layers = P->n_pruned;
    out->phase_tables = P->ptabs, out->n_phase_tables = P->n_ptabs;
    P->ptabs = NULL, P->n_ptabs = 0;
    return 0;
}

static int parse_lines(parser *P, const char *text, size_t len)
{
    const char *p = text, *end = text + len;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        const char *line_end = nl ? nl : end;
        const char *hash = memchr(p, '#', (size_t)(line_end - p));
        const char *cur = p;
        span head;
        if (P->line == INT_MAX)
            return fail(P, P->line, NULL, "too many lines", "fewer than %d lines", INT_MAX);
        P->line++;
        P->line_end = hash ? hash : line_end;
        if (next_token(&cur, hash ? hash : line_end, &head) &&
            read_line(P, cur, hash ? hash : line_end, head))
            return 2;
        p = nl ? nl + 1 : end;
    }
    return 0;
}

/* One parse with the parser's settings (bands, survey, shared decisions) filled in. */
static int parse_into(parser *P, const char *text, size_t len, const char *name, lsqt_assembly *out,
                      lsqt_diag *diag)
{
    lsqt_diag scratch;
    P->name = name ? name : "<input>";
    P->diag = diag ? diag : &scratch;
    memset(P->diag, 0, sizeof *P->diag);
    if (!out)
        return fail(P, 0, NULL, "no assembly to fill", "a non-NULL output");
    memset(out, 0, sizeof *out);

    int rc;
    if (!text && len > 0)
        rc = fail(P, 0, NULL, "no text", "a non-NULL text");
    else
        rc = text ? parse_lines(P, text, len) : 0;
    if (!rc)
        rc = finish_assembly(P);
    if (!rc)
        rc = hand_over(P, out);
    free(P->media);
    free(P->layers);
    for (int i = 0; i < P->n_ptabs; i++)
        lsqt_phase_table_free(&P->ptabs[i]);
    free(P->ptabs);
    return rc;
}

int lsqt_parse_band(const char *text, size_t len, const char *name, lsqt_bands *bands, int band,
                    lsqt_assembly *out, lsqt_diag *diag)
{
    parser P;
    memset(&P, 0, sizeof P);
    P.bands = bands, P.band = band, P.prune_at = -1;
    return parse_into(&P, text, len, name, out, diag);
}

/* What the bands share, from a survey of each: a layer is pruned only where every band
 * is stopped, and a medium keeps its phase model when it scatters in any band (an albedo
 * of 0 in one band is a value, not another model). */
static int survey_bands(const char *text, size_t len, const char *name, lsqt_bands *bands, int *prune_at,
                        unsigned char **keep_phase, lsqt_diag *diag)
{
    int n_layers = -1;
    unsigned char *opaque = NULL;
    for (int b = 0; b < bands->n; b++) {
        parser P;
        memset(&P, 0, sizeof P);
        P.bands = bands, P.band = b, P.prune_at = -1, P.survey = 1;
        lsqt_assembly a;
        if (parse_into(&P, text, len, name, &a, diag)) {
            free(opaque);
            return 2;
        }
        if (n_layers < 0) {
            n_layers = a.n_layers;
            opaque = malloc((size_t)n_layers + 1);
            *keep_phase = calloc((size_t)n_layers + 2, 1);
            if (!opaque || !*keep_phase) {
                lsqt_assembly_free(&a);
                free(opaque);
                return 2;
            }
            memset(opaque, 1, (size_t)n_layers + 1);
        }
        for (int i = 0; i < a.n_layers; i++)
            opaque[i] &= (unsigned char)!lsqt_layer_transmits(&a.layers[i]);
        for (int m = 0; m <= a.n_layers; m++)
            (*keep_phase)[m] |= (unsigned char)(a.media[m].mus > 0);
        lsqt_assembly_free(&a);
    }
    *prune_at = n_layers;
    for (int i = 0; i < n_layers; i++)
        if (opaque[i]) {
            *prune_at = i;
            break;
        }
    free(opaque);
    return 0;
}

/* Every band must be the same stack (layers, models); only numbers differ. The survey
 * makes it so (shared pruning and phase models); this says so if it ever did not. */
static int same_stack(const lsqt_assembly *a0, const lsqt_assembly *ab, parser *P, int band)
{
    int same = a0->n_layers == ab->n_layers;
    for (int i = 0; same && i < a0->n_layers; i++)
        same = a0->layers[i].kind == ab->layers[i].kind;
    for (int m = 0; same && m <= a0->n_layers; m++)
        same = a0->media[m].phase.kind == ab->media[m].phase.kind;
    if (same)
        return 0;
    P->band = band;
    return fail(P, 0, NULL, "the bands make different stacks (an internal error)", "the same layers and models in "
                "every band");
}

/* The tables' paths move from B to A (read by the output checks); B's tables freed. */
static void keep_tables(lsqt_bands *b, lsqt_assembly *a)
{
    if (a) {
        a->tables = b->table_paths, a->n_tables = b->n_tables;
        b->table_paths = NULL;
    }
    for (int i = 0; i < b->n_tables; i++)
        lsqt_band_table_free(&b->tables[i]);
    if (!a)
        for (int i = 0; i < b->n_tables; i++)
            free(b->table_paths[i]);
    free(b->table_paths);
    free(b->tables);
    b->n_tables = 0, b->table_paths = NULL, b->tables = NULL;
}

int lsqt_parse(const char *text, size_t len, const char *name, const double *wl, int n_wl, const char *dir,
               lsqt_assembly *out, lsqt_diag *diag)
{
    if (out)
        memset(out, 0, sizeof *out); /* a failure leaves it empty */
    lsqt_bands bands;
    memset(&bands, 0, sizeof bands);
    bands.n = n_wl, bands.wl = wl, bands.dir = dir;
    /* The band count: --wavelengths, else the first list (a survey of band 1 finds it). */
    int rc = 0;
    if (n_wl == 0) {
        parser P;
        memset(&P, 0, sizeof P);
        P.bands = &bands, P.prune_at = -1, P.survey = 1;
        lsqt_assembly a;
        rc = parse_into(&P, text, len, name, &a, diag);
        if (!rc)
            lsqt_assembly_free(&a);
        if (!rc && bands.n == 0)
            bands.n = 1; /* no list: one band */
    }
    if (!rc && bands.n == 1) {
        rc = lsqt_parse_band(text, len, name, &bands, 0, out, diag);
        keep_tables(&bands, rc ? NULL : out);
        /* one band at one wavelength keeps it (its RAW header, the JSON, the LSS) */
        if (!rc && wl && n_wl == 1 && (out->wavelengths = malloc(sizeof *out->wavelengths)) != NULL)
            out->wavelengths[0] = wl[0];
        return rc;
    }
    int prune_at = -1;
    unsigned char *keep = NULL;
    if (!rc)
        rc = survey_bands(text, len, name, &bands, &prune_at, &keep, diag);
    lsqt_assembly *each = rc ? NULL : calloc((size_t)bands.n, sizeof *each);
    int done = 0;
    for (; !rc && each && done < bands.n; done++) {
        parser P;
        memset(&P, 0, sizeof P);
        P.bands = &bands, P.band = done, P.prune_at = prune_at, P.keep_phase = keep;
        lsqt_diag scratch; /* the notes are band 1's: the others would repeat them */
        rc = parse_into(&P, text, len, name, &each[done], done ? &scratch : diag);
        if (rc && done && diag)
            *diag = scratch;
        if (!rc && done)
            rc = same_stack(&each[0], &each[done], &P, done);
    }
    free(keep);
    if (!rc && (!each || lsqt_assembly_join(each, bands.n, wl, out))) {
        rc = 2;
        if (diag)
            snprintf(diag->error, sizeof diag->error, "%s: error: out of memory", name ? name : "<input>");
    }
    keep_tables(&bands, rc ? NULL : out);
    if (rc)
        for (int b = 0; b < done && b < bands.n; b++)
            lsqt_assembly_free(&each[b]);
    free(each);
    return rc;
}
