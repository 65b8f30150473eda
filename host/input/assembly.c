/* What can be said of a parsed assembly with the model table: its models' names, its
 * canonical text (written with the same table the parser reads, so it always reads
 * back), its hash, and the kernel build options for the models it uses. The parser
 * (lsqt.c) does not call this file: the table is lsqt.c's, and this file reads it. */
#include "lsqt/assembly.h"
#include "lsqt_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *model_name(const lsqt_line_desc *d, int kind, const char *none)
{
    const lsqt_model *m = lsqt_model_of_kind(d, kind);
    return m ? m->name : none;
}

const char *lsqt_bsdf_name(int kind) { return model_name(&lsqt_layer_line, kind, "unknown BSDF"); }

const char *lsqt_phase_name(int kind)
{
    return kind == LSQT_PHASE_NONE ? "none" : model_name(&lsqt_medium_line, kind, "unknown phase");
}

static const char *choice_word(const lsqt_key *k, int v)
{
    for (int i = 0; k->choices[i]; i++)
        if (i == v)
            return k->choices[i];
    return "?";
}

/* " key=value" for every key of the model, read from the line's struct. A table is
 * written by its content, not its file: "@ROWSrows:FNV" (its row count and the hash of its
 * rows, lsqt_phase_table), so two runs differ where their tables do, whatever the files'
 * names; such a text does not read back as input. */
static void write_keys(lsqt_sb *sb, const lsqt_assembly *a, const lsqt_model *m, const unsigned char *base)
{
    for (int i = 0; i < m->n_keys; i++) {
        const lsqt_key *k = &m->keys[i];
        const void *field = base + k->offset;
        if (k->type == LSQT_NUM) {
            lsqt_sb_printf(sb, " %s=%.17g", k->name, *(const double *)field);
        } else if (k->type == LSQT_TABLE) {
            const int t = (int)*(const double *)field;
            if (t >= 1 && t <= a->n_phase_tables)
                lsqt_sb_printf(sb, " %s=@%drows:%016llx", k->name, a->phase_tables[t - 1].n,
                               (unsigned long long)a->phase_tables[t - 1].hash);
            else
                lsqt_sb_printf(sb, " %s=@?", k->name);
        } else {
            int v = k->in_double ? (int)*(const double *)field : *(const int *)field;
            if (k->type == LSQT_INT)
                lsqt_sb_printf(sb, " %s=%d", k->name, v);
            else
                lsqt_sb_printf(sb, " %s=%s", k->name, choice_word(k, v));
        }
    }
}

/* One line: head and its keys, then the model (if any) and its keys. */
static void write_line(lsqt_sb *sb, const lsqt_assembly *a, const lsqt_line_desc *d, const void *obj, int with_model)
{
    const unsigned char *base = obj;
    lsqt_sb_printf(sb, "%s", d->head->name);
    write_keys(sb, a, d->head, base);
    if (with_model) {
        int kind = *(const int *)(const void *)(base + d->kind_offset);
        const lsqt_model *m = lsqt_model_of_kind(d, kind);
        lsqt_sb_printf(sb, " %s", m ? m->name : "?");
        if (m)
            write_keys(sb, a, m, base);
    }
    lsqt_sb_printf(sb, "\n");
}

/* The bands' texts merged token by token: a token the same in every band once, a
 * KEY=VALUE that differs as KEY=V1,V2,... (the bands share their structure). */
static size_t canonical_bands(const lsqt_assembly *a, char *buf, size_t cap)
{
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, cap);
    const int n = a->n_bands;
    char **text = calloc((size_t)n, sizeof *text);
    const char **at = calloc((size_t)n, sizeof *at);
    for (int b = 0; text && at && b < n; b++) {
        size_t len = lsqt_assembly_canonical(&a->band[b], NULL, 0);
        if ((text[b] = malloc(len + 1)) != NULL)
            lsqt_assembly_canonical(&a->band[b], text[b], len + 1);
        at[b] = text[b];
    }
    int ok = text && at;
    for (int b = 0; ok && b < n; b++)
        ok = text[b] != NULL;
    if (ok) {
        lsqt_sb_printf(&sb, "# bands %d", n);
        for (int b = 0; a->wavelengths && b < n; b++)
            lsqt_sb_printf(&sb, "%s%.17g", b ? "," : ": ", a->wavelengths[b]);
        lsqt_sb_printf(&sb, "%s\n", a->wavelengths ? " nm" : "");
    }
    /* bands that are all alike still write one list (the first key), so that the text
     * says how many bands there are and reads back to itself */
    int alike = ok;
    for (int b = 1; alike && b < n; b++)
        alike = strcmp(text[b], text[0]) == 0;
    while (ok && *at[0]) {
        const size_t l0 = strcspn(at[0], " \n");
        int same = 1;
        for (int b = 1; b < n; b++)
            same &= strcspn(at[b], " \n") == l0 && memcmp(at[b], at[0], l0) == 0;
        const char *eq = memchr(at[0], '=', l0);
        if (alike && eq)
            same = alike = 0;
        const size_t key = eq ? (size_t)(eq - at[0]) + 1 : 0;
        lsqt_sb_printf(&sb, "%.*s", (int)(same || !eq ? l0 : key), at[0]);
        for (int b = 0; !same && eq && b < n; b++) {
            const size_t lb = strcspn(at[b], " \n");
            lsqt_sb_printf(&sb, "%s%.*s", b ? "," : "", (int)(lb > key ? lb - key : 0), at[b] + key);
        }
        for (int b = 0; b < n; b++) /* past the token and its separator, written once */
            at[b] += strcspn(at[b], " \n");
        if (*at[0])
            lsqt_sb_printf(&sb, "%c", *at[0]);
        for (int b = 0; b < n; b++)
            at[b] += *at[b] != '\0';
    }
    for (int b = 0; text && b < n; b++)
        free(text[b]);
    free(text);
    free(at);
    return sb.len;
}

size_t lsqt_assembly_canonical(const lsqt_assembly *a, char *buf, size_t cap)
{
    if (a->n_bands > 1)
        return canonical_bands(a, buf, cap);
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, cap);
    for (int i = 0; a->media && i <= a->n_layers; i++) {
        const lsqt_medium *m = &a->media[i];
        write_line(&sb, a, &lsqt_medium_line, m, m->phase.kind != LSQT_PHASE_NONE);
        if (i < a->n_layers)
            write_line(&sb, a, &lsqt_layer_line, &a->layers[i], 1);
    }
    return sb.len;
}

/* 64-bit FNV-1a of the canonical text; 0 if there is no memory for the text. */
uint64_t lsqt_assembly_hash(const lsqt_assembly *a)
{
    size_t n = lsqt_assembly_canonical(a, NULL, 0);
    char *text = malloc(n + 1);
    if (!text)
        return 0;
    lsqt_assembly_canonical(a, text, n + 1);
    uint64_t h = 14695981039346656037ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= (unsigned char)text[i];
        h *= 1099511628211ULL;
    }
    free(text);
    return h;
}

static int uses_phase(const lsqt_assembly *a, int kind)
{
    for (int i = 0; a->media && i <= a->n_layers; i++)
        if (a->media[i].phase.kind == kind)
            return 1;
    return 0;
}

static int uses_bsdf(const lsqt_assembly *a, int kind)
{
    for (int i = 0; i < a->n_layers; i++)
        if (a->layers[i].kind == kind)
            return 1;
    return 0;
}

size_t lsqt_assembly_build_options(const lsqt_assembly *a, char *buf, size_t cap)
{
    lsqt_sb sb;
    lsqt_sb_init(&sb, buf, cap);
    const lsqt_line_desc *descs[] = { &lsqt_medium_line, &lsqt_layer_line };
    for (int d = 0; d < 2; d++) {
        for (int i = 0; i < descs[d]->n_models; i++) {
            const lsqt_model *m = &descs[d]->models[i];
            int used = d == 0 ? uses_phase(a, m->kind) : uses_bsdf(a, m->kind);
            if (m->macro && used)
                lsqt_sb_printf(&sb, "%s-DLSQT_HAS_%s=1", sb.len ? " " : "", m->macro);
        }
    }
    return sb.len;
}
