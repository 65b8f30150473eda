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
    switch (l->kind) {
    case LSQT_BSDF_LAMBERTIAN:
    case LSQT_BSDF_MS_LAMBERTIAN:
        return l->fT > 0;
    case LSQT_BSDF_MS_DIELECTRIC:
        return l->kT > 0;
    case LSQT_BSDF_MS_CONDUCTIVE:
    case LSQT_BSDF_OREN_NAYAR:
        return 0;
    default:
        return 1;
    }
}

int lsqt_assembly_transmits(const lsqt_assembly *a)
{
    for (int i = 0; i < a->n_layers; i++)
        if (!lsqt_layer_transmits(&a->layers[i]))
            return 0;
    return a->n_layers > 0;
}
