/* Device tables: an assembly's layers and media as the kernels read them. */
#ifndef LSQT_TABLES_H
#define LSQT_TABLES_H

#include "lsqt/assembly.h"
#include "lsqt/device_layout.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Fills the device tables of an assembly in double precision (a float kernel gets them
 * rounded by lsqt_tables_to_float). */
void lsqt_device_tables(const lsqt_assembly *a, lsqt_dev_scene *scene, lsqt_dev_medium_d *media,
                        lsqt_dev_layer_d *layers);

/* The phase functions' tables (model_list.h, a TABLE key), as the kernels read them: they
 * follow the n_layers + 1 media in the same buffer (of the kernel's reals), table after
 * table, each its rows' mu, then p, then cdf (lsqt_phase_table), then an index of n + 1
 * reals: per cell j of n equal cells in mu, the row interval [mu[i], mu[i+1]] that holds
 * the cell's lower edge -1 + 2 j / n (so the interval of any mu is found by bisection
 * between two neighbouring cells' entries); a medium with one holds
 * in pp[0] the media from it to the end of the media, in pp[1] its table's offset in reals
 * from there, in pp[2] its row count (lsqt_device_tables). Writes them to out (NULL: only
 * counts) and returns their count of reals. Every band's are the same. */
#define LSQT_PHASE_TABLE_REALS(n) (4 * (size_t)(n) + 1)
size_t lsqt_device_phase_tables(const lsqt_assembly *a, double *out);

/* The float tables of a kernel built without -DLSQT_DOUBLE (same fields, rounded). */
void lsqt_tables_to_float(const lsqt_dev_medium_d *md, lsqt_dev_medium *mf, int n_media,
                          const lsqt_dev_layer_d *ld, lsqt_dev_layer *lf, int n_layers);

/* NULL when the kernels support every model of the assembly, else the first model name. */
const char *lsqt_unsupported_model(const lsqt_assembly *a, int *line);

#ifdef __cplusplus
}
#endif
#endif
