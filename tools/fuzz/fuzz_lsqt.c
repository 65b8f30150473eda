/* libFuzzer target for the LSQT parser: any input must parse or fail cleanly, and what
 * parses must write canonical text that parses back to the same canonical text. Comma
 * lists set bands (lsqt_parse without wavelengths), so every band's parse runs too. */
#include "lsqt/assembly.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Canonical text in a fresh buffer (the caller frees it). */
static char *canonical(const lsqt_assembly *a, size_t *len)
{
    *len = lsqt_assembly_canonical(a, NULL, 0);
    char *text = malloc(*len + 1);
    if (!text)
        abort();
    if (lsqt_assembly_canonical(a, text, *len + 1) != *len)
        abort();
    return text;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    lsqt_assembly a, b;
    lsqt_diag diag;
    int rc = lsqt_parse((const char *)data, size, "fuzz", NULL, 0, ".", &a, &diag);
    if (rc != 0) {
        /* a failure leaves nothing behind and always says why */
        if (rc != 2 || a.n_layers != 0 || a.layers || a.media || !diag.error[0])
            abort();
        return 0;
    }
    if (diag.error[0] || a.n_layers < 1 || !a.layers || !a.media)
        abort();

    size_t n1, n2;
    char *t1 = canonical(&a, &n1);
    if (lsqt_parse(t1, n1, "canonical", NULL, 0, ".", &b, &diag) != 0) {
        fprintf(stderr, "canonical text does not parse: %s\n%s", diag.error, t1);
        abort();
    }
    char *t2 = canonical(&b, &n2);
    if (n1 != n2 || memcmp(t1, t2, n1) != 0 || b.n_pruned_layers != 0 ||
        lsqt_assembly_hash(&a) != lsqt_assembly_hash(&b)) {
        fprintf(stderr, "canonical round trip differs:\n%s---\n%s", t1, t2);
        abort();
    }
    char opts[512];
    if (lsqt_assembly_build_options(&a, opts, sizeof opts) >= sizeof opts)
        abort();
    free(t1);
    free(t2);
    lsqt_assembly_free(&a);
    lsqt_assembly_free(&b);
    return 0;
}
