/* The one list of models (docs/architecture.md, "Adding a model"). Every phase function and
 * BSDF is declared here once: its kind number, its names, its keys (range and default), how
 * its parameters pack into the device tables, and its properties. The parser's key tables,
 * the kind enums, the device-table packing, the angle-only and transmission properties,
 * the kernel build flags (-DLSQT_HAS_<CLASS>_<ID>=1) and the kernels' dispatch
 * (kernels/models.cl) are all expanded from it.
 *
 * Prepended to the OpenCL sources, so only plain C that is also OpenCL C here; the key
 * lists and packing are expanded by the host alone.
 *
 * Phase functions: X(ID, kind number, seed name, short name, kernel prefix, SAMPLER,
 * MIRROR). Kernel prefix p: kernels/phase_*.cl defines p_phase_evalv(m, v, wo, wi) and
 * p_phase_sample(m, v, wo, u1, u2, rng, wi) (the weight p / pdf); SAMPLER is EXACT (draws
 * exactly the phase function: its pdf is its value) or VERTEX (p_phase_vertex fixes a
 * random state per vertex and p_phase_pdf gives the density). MIRROR is 1 when the model
 * is its own mirror image under z -> -z (light from below, host/sim/below.c): so are the
 * phase functions of the scattering angle alone, and SGGX, whose S = diag(Apara^2,
 * Apara^2, Aperp^2) has no xz or yz terms; Null and Lambertian (fR back to the side light
 * came from, fT through, either side); the microsurfaces, whose walks run in the frame of
 * the ray's side (ms_walk flips z, and the uniform heights with c -> 1 - c), whose GGX
 * slopes are symmetric, and whose dielectric takes the relative index seen from that
 * side, which the device tables make from the media on each side. The conductor and
 * Oren-Nayar never transmit, so light from below never meets them from above.
 *
 * A model may carry one table: a key of TYPE TABLE (KEY=@FILE, a file of rows cos theta,
 * value: a phase function's p(cos theta), read by host/input/bands.c, normalised, the same
 * in every band). The engine puts the table on the device after the media (host/sim/
 * tables.c) and owns pp[0..2]: medium_table(m) (kernels/common.cl) is its first real, and
 * (int)m->pp[2] its row count; the model's own packing has pp[3]. */
#ifndef LSQT_MODEL_LIST_H
#define LSQT_MODEL_LIST_H

#define LSQT_PHASES(X)                                                                     \
    X(HG, 1, "HenyeyGreensteinPhase", "HenyeyGreenstein", hg, EXACT, 1)                  \
    X(HG2, 2, "HenyeyGreenstein2Phase", "HenyeyGreenstein2", hg2, EXACT, 1)              \
    X(RAYLEIGH, 3, "RayleighPhase", "Rayleigh", rayleigh, EXACT, 1)                        \
    X(SGGX, 4, "SggxPhase", "Sggx", sggx, VERTEX, 1)                                       \
    X(DRAINE, 5, "DrainePhase", "Draine", draine, EXACT, 1)                                \
    X(TABULATED, 6, "TabulatedPhase", "Tabulated", tabulated, EXACT, 1)

/* BSDFs (NullBsdf, kind 0, is the host's own): X(ID, kind number, seed name, short name,
 * kernel prefix, SAMPLER, MIRROR, TRANSMITS, BANDS, B0, B1, ALPHA). kernels/bsdf_*.cl defines p_evalv(l, wo, wi)
 * and p_pdf(l, wo, wi). SAMPLER is
 * - CLOSED: p_sample(l, wo, u0, u1, u2, wi) returns the weight f / pdf; next-event
 *   estimation evaluates p_evalv;
 * - WALK: a microsurface whose random walk (kernels/microsurface.cl) samples and
 *   estimates every order; the file defines the facets' phase function p_phasev(l, x, u),
 *   the walk's step p_walk_scatter(l, x, rng, r, cross), the index across the facets
 *   p_index(l, side) and the terms of the estimate's first record p_firstv(l, x, u, lam,
 *   lg) (the walk's first vertex, whose escape is averaged over heights);
 * - SINGLE_WALK: as WALK, but single scattering is closed-form: p_firstv is it (the walk
 *   adds orders >= 2), p_evalv is it for one direction, and p_sample samples it (the
 *   layer's use_multiple_scattering=false).
 * TRANSMITS is ALWAYS, NEVER, or the key whose value > 0 lets light
 * through (FT, KT): a layer that transmits nothing prunes what lies below it.
 * BANDS, B0, B1 say how the bands of a block that share their paths (kernels/bands.cl,
 * host/sim/band_blocks.c) may differ at the layer:
 * - SAME: not at all (B0 = B1 = -1);
 * - FACTORS: the value is fs times a unit model towards wo's side and fo times it towards
 *   the other, fs = p[B0], fo = p[B1] (0 where B1 is -1); the unit model (those slots 1)
 *   is sampled by the cosine on the side the block's hero band chooses by its fs : fo;
 * - INDEX: a walk whose facets' albedo depends on a complex index n = p[B0], k = p[B1]:
 *   where no next-event term leaves the layer (under another layer), each band's albedo
 *   weighs the one walk (p_albedo_bands(x, n_row, k_row, wb)).
 * ALPHA is the slot in p[] of a walk's GGX roughness (its Lambda table, lsqt_prepare): 0
 * for every walk (the walk reads p[0]; host/sim/tables.c refuses to build otherwise),
 * NONE for a closed model. */
#define LSQT_BSDFS(X)                                                                                  \
    X(LAMBERTIAN, 1, "LambertianBsdf", "Lambertian", lambertian, CLOSED, 1, FT, FACTORS, 0, 1, NONE)          \
    X(MS_LAMBERTIAN, 2, "MicrosurfaceLambertianBrdf", "MicrosurfaceLambertian", mslambert, WALK, 1, FT, SAME, -1, \
      -1, 0)                                                                                                    \
    X(MS_DIELECTRIC, 3, "MicrosurfaceDielectricBsdf", "MicrosurfaceDielectric", dielectric, SINGLE_WALK, 1, KT,   \
      SAME, -1, -1, 0)                                                                                          \
    X(MS_CONDUCTIVE, 4, "MicrosurfaceConductiveBrdf", "MicrosurfaceConductive", conductor, SINGLE_WALK, 0, NEVER, \
      INDEX, 1, 2, 0)                                                                                           \
    X(OREN_NAYAR, 5, "OrenNayarDiffuseBrdf", "OrenNayarDiffuse", oren_nayar, CLOSED, 0, NEVER, FACTORS, 0, -1, NONE)

#define LSQT_X_PHASE_KIND_(ID, NUM, NAME, ALIAS, P, SAMPLER, MIRROR) LSQT_PHASE_##ID = NUM,
#define LSQT_X_BSDF_KIND_(ID, NUM, NAME, ALIAS, P, SAMPLER, MIRROR, TRANSMITS, BANDS, B0, B1, ALPHA) LSQT_BSDF_##ID = NUM,
enum lsqt_phase_kind { LSQT_PHASE_NONE = 0, LSQT_PHASES(LSQT_X_PHASE_KIND_) };
enum lsqt_bsdf_kind { LSQT_BSDF_NULL = 0, LSQT_BSDFS(LSQT_X_BSDF_KIND_) };
#undef LSQT_X_PHASE_KIND_
#undef LSQT_X_BSDF_KIND_

/* ---- Dispatch (kernels/models.cl, kernels/microsurface.cl) ---------------------------- */

/* LSQT_ON(M): 1 when LSQT_HAS_M is defined as 1, else 0, usable inside a macro (where
 * #ifdef is not) and without variadic macros (OpenCL C 1.2 has none: NVIDIA's compiler
 * refuses them). LSQT_HAS_M defined as 1 pastes to LSQT_ON_1, which is 1; undefined, it
 * pastes to the enum constant LSQT_ON_LSQT_HAS_M, which the list declares 0 for every
 * model. Either way an integer constant: the branches of models not built are dead code. */
#define LSQT_ON_1 1
#define LSQT_ON_CAT_(a, b) a##b
#define LSQT_ON_CAT(a, b) LSQT_ON_CAT_(a, b)
#define LSQT_ON(M) LSQT_ON_CAT(LSQT_ON_, LSQT_HAS_##M)
#define LSQT_ON_PHASE_(ID, num, name, alias, p, sampler, mirror) LSQT_ON_LSQT_HAS_PHASE_##ID = 0,
#define LSQT_ON_BSDF_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_ON_LSQT_HAS_BSDF_##ID = 0,
enum { LSQT_PHASES(LSQT_ON_PHASE_) LSQT_BSDFS(LSQT_ON_BSDF_) LSQT_ON_NONE_ = 0 };

/* The list's SAMPLER column, as text kept or dropped (one argument: the statement's commas
 * are all inside parentheses). LSQT_IF_WALK keeps both kinds of walk; LSQT_IF_SINGLE the
 * walks with closed-form single scattering. */
#define LSQT_IF_CLOSED_CLOSED(s) s
#define LSQT_IF_CLOSED_WALK(s)
#define LSQT_IF_CLOSED_SINGLE_WALK(s)
#define LSQT_IF_WALK_CLOSED(s)
#define LSQT_IF_WALK_WALK(s) s
#define LSQT_IF_WALK_SINGLE_WALK(s) s
#define LSQT_IF_SINGLE_CLOSED(s)
#define LSQT_IF_SINGLE_WALK(s)
#define LSQT_IF_SINGLE_SINGLE_WALK(s) s
#define LSQT_IF_VERTEX_EXACT(s)
#define LSQT_IF_VERTEX_VERTEX(s) s
#define LSQT_IF_EXACT_EXACT(s) s
#define LSQT_IF_EXACT_VERTEX(s)
/* The BANDS column, likewise. */
#define LSQT_IF_FACTORS_SAME(s)
#define LSQT_IF_FACTORS_FACTORS(s) s
#define LSQT_IF_FACTORS_INDEX(s)
#define LSQT_IF_INDEX_SAME(s)
#define LSQT_IF_INDEX_FACTORS(s)
#define LSQT_IF_INDEX_INDEX(s) s

/* Keys, packing and slots are the host's (the kernels read the packed tables); hidden from
 * OpenCL C, which has no variadic macros (LSQT_WORDS). */
#if !defined(__OPENCL_VERSION__) && !defined(__OPENCL_C_VERSION__)

/* ---- Keys: K(ID, FIELD, "name", TYPE, default, lo, lo_open, hi, hi_open, words) --------------
 * TYPE is NUM (a finite double), INT, CHOICE (one of the NULL-terminated words, stored as
 * its index) or TABLE (KEY=@FILE, required; the table's number in the assembly, 1-based). Every key has a slot in its line's v[] (lsqt_phase.v, lsqt_layer.v), named
 * LSQT_<ID>_<FIELD>, in the order of the list, which is also the order keys are written back. */

/* Henyey-Greenstein's g: its peak, (1 + |g|) / (4 pi (1 - |g|)^2), is a next-event
 * estimate's factor, so it must stay well within the tally's 2^44 per contribution
 * (1.6e11 at the bound; g = 1 - 1e-7 overflows it). */
#define LSQT_G_MAX 0.999999
#define LSQT_KEY_G_(K, ID, F, NAME) K(ID, F, NAME, NUM, 0, -LSQT_G_MAX, 0, LSQT_G_MAX, 0, 0)
#define LSQT_KEY_FRACTION_(K, ID, F, NAME, DEF) K(ID, F, NAME, NUM, DEF, 0, 0, 1, 0, 0)

#define LSQT_KEYS_HG(K, ID) LSQT_KEY_G_(K, ID, g, "g")
#define LSQT_KEYS_HG2(K, ID) \
    LSQT_KEY_G_(K, ID, g0, "g0") LSQT_KEY_G_(K, ID, g1, "g1") LSQT_KEY_FRACTION_(K, ID, b, "b", 0)
#define LSQT_KEYS_RAYLEIGH(K, ID) K(ID, rho, "rho", NUM, 0, -1, 0, 1, 0, 0)
#define LSQT_KEYS_SGGX(K, ID)                         \
    K(ID, apara, "Apara", NUM, 1, 0, 1, 1e6, 0, 0) \
    K(ID, aperp, "Aperp", NUM, 1, 0, 1, 1e6, 0, 0) \
    K(ID, type, "type", CHOICE, 0, 0, 0, 0, 0, LSQT_WORDS("Specular", "Diffuse"))
/* Draine's alpha: 0 is Henyey-Greenstein, 1 at g = 0 is Rayleigh's shape; the bound only
 * keeps the numbers sane (the sampler's acceptance stays above 1/3 for any alpha). */
#define LSQT_KEYS_DRAINE(K, ID) LSQT_KEY_G_(K, ID, g, "g") K(ID, alpha, "alpha", NUM, 0, 0, 0, 1e3, 0, 0)
/* TabulatedPhase: p(cos theta) from a table (required: no default) */
#define LSQT_KEYS_TABULATED(K, ID) K(ID, table, "table", TABLE, 0, 0, 0, 0, 0, 0)

/* Microsurfaces: alpha's default 0.5; iter_count's default 0 means "auto" (resolved from
 * alpha once the line is read). */
#define LSQT_KEY_ALPHA_(K, ID) K(ID, alpha, "alpha", NUM, 0.5, 0, 1, 100, 0, 0)
#define LSQT_KEY_ITER_(K, ID) K(ID, iter_count, "iter_count", INT, 0, 1, 0, 128, 0, 0)
#define LSQT_KEY_MULTIPLE_(K, ID, DEF) \
    K(ID, multiple_scattering, "use_multiple_scattering", CHOICE, DEF, 0, 0, 0, 0, LSQT_WORDS("false", "true"))

#define LSQT_KEYS_LAMBERTIAN(K, ID) LSQT_KEY_FRACTION_(K, ID, fR, "fR", 1) LSQT_KEY_FRACTION_(K, ID, fT, "fT", 0)
#define LSQT_KEYS_MS_LAMBERTIAN(K, ID)                                                                      \
    LSQT_KEY_ALPHA_(K, ID) LSQT_KEY_FRACTION_(K, ID, fR, "fR", 1) LSQT_KEY_FRACTION_(K, ID, fT, "fT", 0) \
    LSQT_KEY_ITER_(K, ID) LSQT_KEY_MULTIPLE_(K, ID, 1)
#define LSQT_KEYS_MS_DIELECTRIC(K, ID)                                                                      \
    LSQT_KEY_ALPHA_(K, ID) LSQT_KEY_FRACTION_(K, ID, kR, "kR", 1) LSQT_KEY_FRACTION_(K, ID, kT, "kT", 1) \
    LSQT_KEY_ITER_(K, ID) LSQT_KEY_MULTIPLE_(K, ID, 1)
#define LSQT_KEYS_MS_CONDUCTIVE(K, ID) LSQT_KEY_ALPHA_(K, ID) LSQT_KEY_ITER_(K, ID) LSQT_KEY_MULTIPLE_(K, ID, 0)
#define LSQT_KEYS_OREN_NAYAR(K, ID) \
    LSQT_KEY_FRACTION_(K, ID, fR, "fR", 1) K(ID, sigma, "sigma", NUM, 0.1, 0, 0, 0.8, 0, 0)

/* ---- Packing into the device tables (host only) -------------------------------------------
 * A phase function's pp[4] from its key values v (indexed LSQT_<ID>_<key>); a BSDF's p[8]
 * from its key values v and the media up (above) and down (below). Doubles; the float tables
 * are rounded from them. */
#define LSQT_PACK_HG(v, pp) pp[0] = v[LSQT_HG_g];
#define LSQT_PACK_HG2(v, pp) pp[0] = v[LSQT_HG2_g0], pp[1] = v[LSQT_HG2_g1], pp[2] = v[LSQT_HG2_b];
#define LSQT_PACK_RAYLEIGH(v, pp) pp[0] = v[LSQT_RAYLEIGH_rho] / (2.0 - v[LSQT_RAYLEIGH_rho]); /* gamma, as the seed */
/* S = diag(Apara^2, Apara^2, Aperp^2), scaled to a largest entry of 1 (the phase function
 * does not change with the scale of S, and float keeps its range) */
#define LSQT_PACK_SGGX(v, pp)                                                           \
    {                                                                                   \
        double a_ = v[LSQT_SGGX_apara] > v[LSQT_SGGX_aperp] ? v[LSQT_SGGX_apara] : v[LSQT_SGGX_aperp]; \
        pp[0] = (v[LSQT_SGGX_apara] / a_) * (v[LSQT_SGGX_apara] / a_);                \
        pp[1] = (v[LSQT_SGGX_aperp] / a_) * (v[LSQT_SGGX_aperp] / a_);                \
        pp[2] = v[LSQT_SGGX_type];                                                      \
    }
/* g, alpha and the normalisation 1 / (1 + alpha (1 + 2 g^2) / 3) (kernels/phase_draine.cl) */
#define LSQT_PACK_DRAINE(v, pp)                                                                      \
    pp[0] = v[LSQT_DRAINE_g], pp[1] = v[LSQT_DRAINE_alpha],                                          \
    pp[2] = 1.0 / (1.0 + v[LSQT_DRAINE_alpha] * (1.0 + 2.0 * v[LSQT_DRAINE_g] * v[LSQT_DRAINE_g]) / 3.0);
/* the table and its place are the engine's (pp[0..2], above) */
#define LSQT_PACK_TABULATED(v, pp) pp[3] = 0;

#define LSQT_PACK_LAMBERTIAN(v, up, down, p) p[0] = v[LSQT_LAMBERTIAN_fR], p[1] = v[LSQT_LAMBERTIAN_fT];
#define LSQT_PACK_MS_LAMBERTIAN(v, up, down, p) \
    p[0] = v[LSQT_MS_LAMBERTIAN_alpha], p[1] = v[LSQT_MS_LAMBERTIAN_fR], p[2] = v[LSQT_MS_LAMBERTIAN_fT];
/* alpha, the index below relative to the one above, the Fresnel scales */
#define LSQT_PACK_MS_DIELECTRIC(v, up, down, p)                                                \
    p[0] = v[LSQT_MS_DIELECTRIC_alpha], p[1] = down->eta / up->eta, p[2] = v[LSQT_MS_DIELECTRIC_kR], \
    p[3] = v[LSQT_MS_DIELECTRIC_kT];
/* alpha, and the metal's complex index relative to the medium above */
#define LSQT_PACK_MS_CONDUCTIVE(v, up, down, p) \
    p[0] = v[LSQT_MS_CONDUCTIVE_alpha], p[1] = down->eta / up->eta, p[2] = down->mua / up->eta;
#define LSQT_PACK_OREN_NAYAR(v, up, down, p) p[0] = v[LSQT_OREN_NAYAR_fR], p[1] = v[LSQT_OREN_NAYAR_sigma];

#define LSQT_TRANSMITS_ALWAYS(ID, v) 1
#define LSQT_TRANSMITS_NEVER(ID, v) 0
#define LSQT_TRANSMITS_FT(ID, v) (v[LSQT_##ID##_fT] > 0)
#define LSQT_TRANSMITS_KT(ID, v) (v[LSQT_##ID##_kT] > 0)

/* A choice key's words: a NULL-terminated array (host only). */
#define LSQT_WORDS(...) ((const char *const[]){ __VA_ARGS__, 0 })

/* The slots of each model's keys in v[]: LSQT_<ID>_<key>, and LSQT_<ID>_N_KEYS (host
 * only: the kernels read the packed tables). */
#define LSQT_X_KEY_SLOT_(ID, F, NAME, TYPE, DEF, LO, LO_OPEN, HI, HI_OPEN, WORDS) LSQT_##ID##_##F,
#define LSQT_X_SLOTS_(ID) enum { LSQT_KEYS_##ID(LSQT_X_KEY_SLOT_, ID) LSQT_##ID##_N_KEYS };
#define LSQT_X_PHASE_SLOTS_(ID, NUM, NAME, ALIAS, P, SAMPLER, MIRROR) LSQT_X_SLOTS_(ID)
#define LSQT_X_BSDF_SLOTS_(ID, NUM, NAME, ALIAS, P, SAMPLER, MIRROR, TRANSMITS, BANDS, B0, B1, ALPHA) LSQT_X_SLOTS_(ID)
LSQT_PHASES(LSQT_X_PHASE_SLOTS_)
LSQT_BSDFS(LSQT_X_BSDF_SLOTS_)
#undef LSQT_X_PHASE_SLOTS_
#undef LSQT_X_BSDF_SLOTS_
#undef LSQT_X_SLOTS_
#undef LSQT_X_KEY_SLOT_

#endif /* not OpenCL C */

#endif
