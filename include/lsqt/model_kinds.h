/* Model kind numbers, shared by the host and the kernels (prepended to the OpenCL
 * sources, so only plain C that is also OpenCL C here). */
#ifndef LSQT_MODEL_KINDS_H
#define LSQT_MODEL_KINDS_H

enum lsqt_phase_kind {
    LSQT_PHASE_NONE = 0,
    LSQT_PHASE_HG = 1,
    LSQT_PHASE_HG2 = 2,
    LSQT_PHASE_RAYLEIGH = 3,
    LSQT_PHASE_SGGX = 4
};

enum lsqt_bsdf_kind {
    LSQT_BSDF_NULL = 0,
    LSQT_BSDF_LAMBERTIAN = 1,
    LSQT_BSDF_MS_LAMBERTIAN = 2,
    LSQT_BSDF_MS_DIELECTRIC = 3,
    LSQT_BSDF_MS_CONDUCTIVE = 4,
    LSQT_BSDF_OREN_NAYAR = 5
};

#endif
