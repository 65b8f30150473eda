/* Every model's sampler against its own evaluation, through the harness kernels (the
 * same code the walk runs): a chi-square goodness-of-fit test on an equal-area
 * (cos theta, phi) grid, the sample weight equal to f / pdf, and the integral of f over
 * the sphere equal to the model's albedo. */
#include "cl_fixture.h"
#include "quadrature.h"
#include "ref_conductor.h"

#define PI 3.14159265358979323846
#define NU 16
#define NPHI 16
#define SUB 24 /* midpoints per cell side for the expected counts: 6 could not resolve a grazing GGX lobe */
#define NSAMPLES 100000

static cl_program prog;

typedef struct {
    const char *name;
    int use_phase;
    lsqt_dev_layer layer;
    lsqt_dev_medium medium;
    double wo[3];
    double albedo;
    double quad_tol; /* allowed quadrature error of the normalisation checks, 0: 2e-5 */
} model_case;

static void run_kernel(const char *name, const model_case *m, cl_mem extra_in, cl_mem out, size_t n)
{
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, name, &e);
    cl_mem bl = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof m->layer,
                               (void *)&m->layer, &e);
    cl_mem bm = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof m->medium,
                               (void *)&m->medium, &e);
    float wo[3] = {(float)m->wo[0], (float)m->wo[1], (float)m->wo[2]};
    cl_uint seed = 12345u;
    clSetKernelArg(k, 0, sizeof bl, &bl);
    clSetKernelArg(k, 1, sizeof bm, &bm);
    clSetKernelArg(k, 2, sizeof(cl_int), &m->use_phase);
    for (int i = 0; i < 3; i++) clSetKernelArg(k, (cl_uint)(3 + i), sizeof(float), &wo[i]);
    if (extra_in) clSetKernelArg(k, 6, sizeof extra_in, &extra_in);
    else clSetKernelArg(k, 6, sizeof seed, &seed);
    clSetKernelArg(k, 7, sizeof out, &out);
    e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &n, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clFinish(fixture_cx.queue);
    CHECK(e == CL_SUCCESS, "%s: %s failed: %d", m->name, name, (int)e);
    clReleaseMemObject(bl);
    clReleaseMemObject(bm);
    clReleaseKernel(k);
}

static int cell_of(double x, double y, double z)
{
    int iu = (int)((z + 1.0) * 0.5 * NU);
    double phi = atan2(y, x);
    if (phi < 0) phi += 2 * PI;
    int ip = (int)(phi / (2 * PI) * NPHI);
    iu = iu < 0 ? 0 : iu >= NU ? NU - 1 : iu;
    ip = ip < 0 ? 0 : ip >= NPHI ? NPHI - 1 : ip;
    return iu * NPHI + ip;
}

/* Upper tail of chi-square with k dof (Wilson-Hilferty). */
static double chi2_tail(double x, double k)
{
    double z = (pow(x / k, 1.0 / 3.0) - (1 - 2 / (9 * k))) / sqrt(2 / (9 * k));
    return 0.5 * erfc(z / sqrt(2.0));
}

/* The integrals of f and of the pdf over the sphere: Gauss-Legendre in cos of the angle
 * to an axis, on panels that split at the plane normal to it (where a BSDF jumps
 * between reflection and transmission) and, for a BSDF, grade towards mu = +-cos theta_o
 * (a specular lobe and its transmitted or below-horizon part), times an even rule in
 * azimuth. The axis is z for a BSDF and the forward direction -wo for a phase function,
 * so a peaked lobe is resolved. */
#define QN 16 /* nodes per panel */
#define QPHI 512
static void sphere_integrals(const model_case *m, double *f_int, double *pdf_int)
{
    double gx[QN], gw[QN], ax[3] = {0, 0, 1}, u[3], v[3];
    gauss_legendre(QN, gx, gw);
    double edges[32];
    int np = 0;
    edges[0] = -1.0;
    if (m->use_phase) {
        double n = sqrt(m->wo[0] * m->wo[0] + m->wo[1] * m->wo[1] + m->wo[2] * m->wo[2]);
        for (int i = 0; i < 3; i++) ax[i] = -m->wo[i] / n;
        /* HG peaks at mu = 1 about -wo: panels graded towards it */
        const double cut[] = {-0.5, 0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995};
        for (int i = 0; i < 9; i++) edges[++np] = cut[i];
    } else {
        double mp = fabs(m->wo[2]);
        const double off[] = {-0.1, -0.02, 0.0, 0.02, 0.1};
        for (int sgn = -1; sgn <= 1; sgn += 2)
            for (int i = 0; i < 5; i++) {
                double c = sgn < 0 ? -mp - off[4 - i] : mp + off[i];
                if (sgn > 0 && edges[np] < 0.0) edges[++np] = 0.0;
                if (c > edges[np] + 1e-3 && c < 1.0 - 1e-3 && fabs(c) > 1e-3) edges[++np] = c;
            }
        if (edges[np] < 0.0) edges[++np] = 0.0;
    }
    edges[++np] = 1.0;
    /* u, v: an orthonormal pair normal to the axis */
    double t[3] = {fabs(ax[0]) < 0.9 ? 1.0 : 0.0, fabs(ax[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    u[0] = ax[1] * t[2] - ax[2] * t[1], u[1] = ax[2] * t[0] - ax[0] * t[2], u[2] = ax[0] * t[1] - ax[1] * t[0];
    double un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; i++) u[i] /= un;
    v[0] = ax[1] * u[2] - ax[2] * u[1], v[1] = ax[2] * u[0] - ax[0] * u[2], v[2] = ax[0] * u[1] - ax[1] * u[0];
    const size_t ng = (size_t)np * QN * QPHI;
    float *dirs = malloc(ng * 4 * sizeof *dirs), *fp = malloc(ng * 2 * sizeof *fp);
    double *wt = malloc(ng * sizeof *wt);
    size_t q = 0;
    for (int p = 0; p < np; p++)
        for (int i = 0; i < QN; i++) {
            double h = 0.5 * (edges[p + 1] - edges[p]), mu = edges[p] + h * (gx[i] + 1), s = sqrt(1 - mu * mu);
            for (int j = 0; j < QPHI; j++, q++) {
                double phi = 2 * PI * (j + 0.5) / QPHI;
                for (int c = 0; c < 3; c++)
                    dirs[4 * q + c] = (float)(mu * ax[c] + s * (cos(phi) * u[c] + sin(phi) * v[c]));
                dirs[4 * q + 3] = 0;
                wt[q] = h * gw[i] * 2 * PI / QPHI;
            }
        }
    cl_int e = CL_SUCCESS;
    cl_mem bd = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, ng * 16, dirs, &e);
    cl_mem bf = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, ng * 8, NULL, &e);
    run_kernel("harness_eval", m, bd, bf, ng);
    clEnqueueReadBuffer(fixture_cx.queue, bf, CL_TRUE, 0, ng * 8, fp, 0, NULL, NULL);
    *f_int = *pdf_int = 0;
    for (size_t k = 0; k < ng; k++) {
        *f_int += wt[k] * fp[2 * k];
        *pdf_int += wt[k] * fp[2 * k + 1];
    }
    clReleaseMemObject(bd);
    clReleaseMemObject(bf);
    free(dirs);
    free(fp);
    free(wt);
}

static void test_model(const model_case *m)
{
    cl_int e = CL_SUCCESS;
    /* Evaluate f and pdf on SUB x SUB midpoints of every cell. */
    const size_t ng = (size_t)NU * SUB * NPHI * SUB;
    float *grid = malloc(ng * 4 * sizeof *grid), *fp = malloc(ng * 2 * sizeof *fp);
    for (size_t iu = 0; iu < (size_t)NU * SUB; iu++)
        for (size_t ip = 0; ip < (size_t)NPHI * SUB; ip++) {
            double z = -1.0 + 2.0 * (iu + 0.5) / (NU * SUB), phi = 2 * PI * (ip + 0.5) / (NPHI * SUB);
            double s = sqrt(1 - z * z);
            float *g = grid + 4 * (iu * NPHI * SUB + ip);
            g[0] = (float)(s * cos(phi));
            g[1] = (float)(s * sin(phi));
            g[2] = (float)z;
            g[3] = 0;
        }
    cl_mem bg = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, ng * 16, grid, &e);
    cl_mem bf = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, ng * 8, NULL, &e);
    run_kernel("harness_eval", m, bg, bf, ng);
    clEnqueueReadBuffer(fixture_cx.queue, bf, CL_TRUE, 0, ng * 8, fp, 0, NULL, NULL);
    double expected[NU * NPHI] = {0}, dA = 4 * PI / (double)ng;
    for (size_t i = 0; i < ng; i++) {
        int c = cell_of(grid[4 * i], grid[4 * i + 1], grid[4 * i + 2]);
        expected[c] += fp[2 * i + 1] * dA * NSAMPLES;
    }
    /* Normalisation, from the accurate rule: the quadrature has converged (96 and 192
     * nodes agree to 1e-8; HG's pole in cos lies at 1.013 for g = 0.85). What remains is
     * float evaluation near a peak: 1 + g^2 - 2 g cos cancels to 0.0225 there, so 1e-7
     * rounding in cos becomes 1e-5 in the value; g = 0.85 integrates to 1 + 3.5e-6. The
     * bound 2e-5 still sees a model value off by 1e-4 (a 0.5 % error is 250 times it). */
    double qf = 0, qp = 0;
    sphere_integrals(m, &qf, &qp);
    const double tol = m->quad_tol > 0 ? m->quad_tol : 2e-5;
    CHECK(fabs(qf - m->albedo) <= tol * m->albedo + 1e-9, "%s: integral of f = %.9f, albedo %.9f", m->name, qf,
          m->albedo);
    CHECK(fabs(qp - 1.0) <= tol, "%s: integral of pdf = %.9f", m->name, qp);

    /* Sample, bin, and compare weights with f / pdf at the sampled directions. */
    float *smp = malloc((size_t)NSAMPLES * 4 * sizeof *smp), *fs = malloc((size_t)NSAMPLES * 2 * sizeof *fs);
    cl_mem bs = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_WRITE, (size_t)NSAMPLES * 16, NULL, &e);
    cl_mem bfs = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, (size_t)NSAMPLES * 8, NULL, &e);
    run_kernel("harness_sample", m, NULL, bs, NSAMPLES);
    run_kernel("harness_eval", m, bs, bfs, NSAMPLES);
    clEnqueueReadBuffer(fixture_cx.queue, bs, CL_TRUE, 0, (size_t)NSAMPLES * 16, smp, 0, NULL, NULL);
    clEnqueueReadBuffer(fixture_cx.queue, bfs, CL_TRUE, 0, (size_t)NSAMPLES * 8, fs, 0, NULL, NULL);
    double observed[NU * NPHI] = {0};
    int bad_weight = 0, bad_dir = 0;
    for (int i = 0; i < NSAMPLES; i++) {
        const float *s = smp + 4 * i;
        double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        if (!(fabs(len - 1) < 1e-4)) bad_dir++;
        double ratio = fs[2 * i + 1] > 0 ? fs[2 * i] / fs[2 * i + 1] : 0;
        if (!(fabs(s[3] - ratio) <= 1e-4 * ratio + 1e-6)) bad_weight++;
        observed[cell_of(s[0], s[1], s[2])] += 1;
    }
    CHECK(bad_dir == 0, "%s: %d samples are not unit vectors", m->name, bad_dir);
    CHECK(bad_weight == 0, "%s: %d sample weights differ from f/pdf", m->name, bad_weight);
    /* Pool cells with small expectations, then chi-square. */
    double chi2 = 0, pool_e = 0, pool_o = 0;
    int dof = -1;
    for (int c = 0; c < NU * NPHI; c++) {
        if (expected[c] < 20) {
            pool_e += expected[c];
            pool_o += observed[c];
            continue;
        }
        chi2 += (observed[c] - expected[c]) * (observed[c] - expected[c]) / expected[c];
        dof++;
    }
    if (pool_e > 0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof++;
    }
    double p = dof > 0 ? chi2_tail(chi2, dof) : 0;
    CHECK(dof > 5 && p > 1e-3, "%s: chi2 = %.1f with %d dof, p = %.3g", m->name, chi2, dof, p);
    printf("%-28s integral of f %.9f (albedo %.9f), of pdf %.9f  chi2 %.1f / %d dof  p = %.3f\n", m->name, qf,
           m->albedo, qp, chi2, dof, p);
    clReleaseMemObject(bg);
    clReleaseMemObject(bf);
    clReleaseMemObject(bs);
    clReleaseMemObject(bfs);
    free(grid);
    free(fp);
    free(smp);
    free(fs);
}

int main(void)
{
    fixture_open();
    prog = fixture_build("-cl-std=CL1.2 -DLSQT_HAS_BSDF_LAMBERTIAN=1 -DLSQT_HAS_PHASE_HG=1 -DLSQT_HAS_BSDF_MS_CONDUCTIVE=1");
    if (!prog) return check_finish("test_models");
    const double hg_g[] = {0.0, 0.3, -0.6, 0.85};
    for (int i = 0; i < 4; i++) {
        model_case m = {.name = "HenyeyGreenstein", .use_phase = 1, .wo = {0.3, -0.2, 0.9327379}, .albedo = 1.0};
        m.medium.phase_kind = LSQT_PHASE_HG;
        m.medium.pp[0] = (float)hg_g[i];
        test_model(&m);
    }
    const double lam[][2] = {{0.6, 0.0}, {0.3, 0.5}, {0.0, 1.0}};
    const double wos[][3] = {{0.0, 0.0, 1.0}, {0.6, 0.0, -0.8}, {0.99, 0.0, 0.14106736}};
    for (int i = 0; i < 3; i++) {
        model_case m = {.name = "Lambertian", .wo = {wos[i][0], wos[i][1], wos[i][2]}, .albedo = lam[i][0] + lam[i][1]};
        m.layer.kind = LSQT_BSDF_LAMBERTIAN;
        m.layer.p[0] = (float)lam[i][0];
        m.layer.p[1] = (float)lam[i][1];
        test_model(&m);
    }
    /* The single-scattering GGX conductor: its albedo from the independent reference
     * (ref_conductor.h, converged to 1e-5 by its quadrature), silver's index. The
     * samples below the horizon carry weight 0 and the pdf covers them (it integrates to
     * 1 over the sphere). alpha 0.05 is checked in test_conductor (values) only: this
     * grid's expected counts cannot resolve its lobe. */
    const double calpha[] = {0.3, 1.0, 2.4}, cdeg[] = {0, 60, 85};
    for (int ia = 0; ia < 3; ia++)
        for (int it = 0; it < 3; it++) {
            double th = cdeg[it] * PI / 180;
            /* At 85 degrees the lobe hugs the horizon and the rule converges slowly (512 vs
             * 128 azimuths moved the integrals by up to 7e-4; what is left is below 4e-4):
             * there the bound is 5e-4, still ten times below a 0.5 % model error. */
            model_case m = {.name = "Conductor", .wo = {sin(th), 0.0, cos(th)},
                            .albedo = ref_albedo(calpha[ia], 0.051585 + 3.9046 * I, th, 64),
                            .quad_tol = cdeg[it] > 80 ? 5e-4 : 0.0};
            m.layer.kind = LSQT_BSDF_MS_CONDUCTIVE;
            m.layer.p[0] = (float)calpha[ia];
            m.layer.p[1] = 0.051585f;
            m.layer.p[2] = 3.9046f;
            printf("alpha %.2g, theta_o %2.0f: ", calpha[ia], cdeg[it]);
            test_model(&m);
        }
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_models");
}
