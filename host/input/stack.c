/* The parsed stack itself: freeing it, and whether light can cross a layer or the whole
 * stack (the parser prunes with it; the runs decide on transmission with it). */
#include "lsqt/assembly.h"

#include <stdlib.h>
#include <string.h>

void lsqt_assembly_free(lsqt_assembly *a)
{
    if (!a)
        return;
    free(a->layers);
    free(a->media);
    memset(a, 0, sizeof *a);
}

int lsqt_layer_transmits(const lsqt_layer *l)
{
#define TRANSMITS(ID, num, name, alias, prefix, sampler, mirror, transmits) \
    if (l->kind == LSQT_BSDF_##ID)                                          \
        return LSQT_TRANSMITS_##transmits(ID, l->v);
    LSQT_BSDFS(TRANSMITS)
#undef TRANSMITS
    return 1; /* NullBsdf */
}

int lsqt_assembly_transmits(const lsqt_assembly *a)
{
    for (int i = 0; i < a->n_layers; i++)
        if (!lsqt_layer_transmits(&a->layers[i]))
            return 0;
    return a->n_layers > 0;
}
