/* Device tables: an assembly's layers and media as the kernels read them. */
#ifndef LSQT_TABLES_H
#define LSQT_TABLES_H

#include "lsqt/assembly.h"
#include "lsqt/device_layout.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fills the device tables of an assembly in double precision (a float kernel gets them
 * rounded by lsqt_tables_to_float). */
void lsqt_device_tables(const lsqt_assembly *a, lsqt_dev_scene *scene, lsqt_dev_medium_d *media,
                        lsqt_dev_layer_d *layers);

/* The float tables of a kernel built without -DLSQT_DOUBLE (same fields, rounded). */
void lsqt_tables_to_float(const lsqt_dev_medium_d *md, lsqt_dev_medium *mf, int n_media,
                          const lsqt_dev_layer_d *ld, lsqt_dev_layer *lf, int n_layers);

/* NULL when the kernels support every model of the assembly, else the first model name. */
const char *lsqt_unsupported_model(const lsqt_assembly *a, int *line);

#ifdef __cplusplus
}
#endif
#endif
