// lssview: previews of an LSS file (docs/guide.md). A sphere under a few directional lights,
// direct lighting only, from the BSDF estimates of the LSS (read by the project's C
// library, no second reader); or, with --error, the relative standard error of every
// pixel's value in false colour with a colour bar.
//
// Camera and scene. Orthographic camera looking down -z (view direction V = +z towards
// the camera, +x right, +y up) at a unit sphere whose radius is 0.45 of the image width,
// centred. Pixel (i, j) (row j from the top) has its centre at
//   x = (i + 0.5 - dim/2) / (0.45 dim),  y = (dim/2 - j - 0.5) / (0.45 dim),
// and the normal n = (x, y, sqrt(1 - x² - y²)) where x² + y² < 1 (black outside).
// Value = sum over lights L of E_L · f(wo, wi_L) · max(cos θi_L, 0), in the local frame
// z = n, x = V projected onto the tangent plane: wo = V = (sin θo, 0, cos θo) as the
// slices store it (paths enter along -wo, i.e. from the camera), wi_L = the direction
// towards light L. Light below the local horizon adds nothing (direct light only, the
// sphere is opaque to it), so only the reflection half of the BSDF is used.
//
// Interpolation of f(θo, wi) between the estimates (isotropy: f depends on θo, θi, Δφ,
// so every direction is expressed in the slice frame where wo lies at azimuth 0):
//  - in θo: linearly between the two slices θ_a <= θo <= θ_b (sorted, slices from below
//    ignored). To keep a sharp lobe from splitting into two ghosts, wi is carried to each
//    slice by the disk automorphism of its projection p = (x, y) on the unit disk,
//    p -> (p + c)/(1 + c p) (complex, c = (s - s_k)/(1 - s s_k), s = sin θo, s_k =
//    sin θ_k): real c keeps the plane of incidence and the y-mirror symmetry, the horizon
//    stays the horizon, it is the identity at θo = θ_k, and it sends the mirror direction
//    of θo, p = -s, exactly onto the slice's mirror direction -s_k.
//  - within a slice: the stored directions (y >= 0) and their mirror images (y -> -y,
//    the BSDF is mirror symmetric about the plane of wo), upper hemisphere only, are
//    scattered data. f at q is the weighted mean of the K = 8 nearest (chord distance d),
//    weight (1 - (d/R)²)² with R = min(distance of the 9th nearest, the --max-gap radius):
//    a neighbour enters or leaves the set with weight 0, so the result is continuous in
//    q, and it is a convex combination, so it never leaves the range of its neighbours
//    (no spikes, no overshoot; a constant BSDF comes out exactly constant).
//  - θo beyond the last slice θ_max (the default slices end at 0.99·90°·(N-1)/N, so the
//    sphere's rim has no slice): by default the last slice is held, f(θo, wi) = f(θ_max,
//    wi) for θo in (θ_max, 90°] (its estimates as they are, no warp, no extrapolation),
//    and the summary line says how many pixels that is; a Lambertian's f is constant, so
//    it is exact there. --strict marks the rim uncovered instead.
//  - no stored direction within the --max-gap angle (default 40°) of q (both modes), or
//    θo below the first slice, or beyond the last with --strict: the pixel is not
//    covered by the LSS and is marked magenta (1, 0, 1), never filled in.
// Errors (--error): the estimates of one slice share their paths, so their errors are
// combined as fully correlated (err = the same weighted mean of the errors, summed over
// lights like the values): an upper bound that scales as 1/sqrt(paths) like each error.
// A held rim pixel gets the last slice's error, as it gets its values.
// Bands (a run with --wavelengths or lists of values): every band is interpolated with
// the same weights, and the pixel's colour is R, G, B as they are (three unnamed bands) or
// the linear sRGB of its spectrum (colour.h: CIE 1931 under D65, a flat spectrum exactly
// grey), each channel then tone mapped as one band's value is; --error shows the relative
// error of the luminance Y = sum of y_b v_b (Rec. 709 weights, or Y of each band's unit
// spectrum), the bands' errors combined as fully correlated like the directions'.
// --channel K renders band K alone, exactly as a one-band LSS of its values.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <glm/glm.hpp>

#include "lsqt/colour.h"
#include "lsqt/lss.h"
#include "lsqt/state.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

namespace {

constexpr int K_NEAR = 8;
constexpr double SPHERE_FRAC = 0.45; // sphere radius / image width

struct Light {
    glm::dvec3 dir; // unit, towards the light
    double E;       // irradiance on a surface facing it
};

struct Sample {
    glm::dvec3 d;
    size_t row; // its values: f[row * nb + b], e[row * nb + b] (a mirror image shares them)
};

struct Slice {
    double theta, s;
    std::vector<Sample> pts; // upper hemisphere, both mirror images
    std::vector<double> f, e; // per stored direction, nb bands each
};

struct Options {
    std::string in, out;
    int dim = 512;
    double mul = 1.0;
    bool error = false;
    double error_max = 0.0; // 0: automatic
    double max_gap_deg = 40.0;
    bool quiet = false;
    bool strict = false; // no held rim: θo beyond the last slice is uncovered
    int channel = -1;    // --channel K: band K alone, in grey (-1: every band, in colour)
    std::vector<Light> lights;
};

void usage(FILE *f)
{
    std::fprintf(f,
                 "usage: lssview [OPTIONS] IN.lss\n"
                 "Renders a sphere with the BSDF of IN.lss under directional lights (direct light only).\n"
                 "  -o, --output PATH    image to write, any format OpenImageIO writes (default IN.lss.png,\n"
                 "                       IN.lss.error.png with --error), written atomically, never over\n"
                 "                       IN.lss; .exr/.hdr get linear values, others are tone mapped\n"
                 "                       (1 - exp(-v)) and sRGB encoded\n"
                 "  --image-dim N        image width and height in pixels (512; 16-8192)\n"
                 "  --image-mul M        brightness: values are multiplied by M (1)\n"
                 "  --error              the relative standard error of each pixel in false colour, with a bar\n"
                 "  --error-max E        top of the colour bar, relative (default: the largest error, rounded up)\n"
                 "  --light X,Y,Z,E      a directional light towards (X, Y, Z) (camera space: +x right, +y up,\n"
                 "                       +z to the camera) of irradiance E; repeat it; replaces the default lights\n"
                 "                       (-1,1,1.2) E=2.5, (1,0.2,0.6) E=0.8, (0,1,-0.3) E=1.2\n"
                 "  --max-gap DEG        a direction with no estimate within DEG degrees is uncovered (40)\n"
                 "  --channel K          a run with bands: band K alone (0-based), in grey; without it the\n"
                 "                       bands make the colour: R, G, B as they are, a spectrum (--wavelengths)\n"
                 "                       as linear sRGB (CIE 1931, D65), with --error the luminance's error\n"
                 "  --strict             the rim beyond the last slice's view angle is uncovered (magenta)\n"
                 "                       instead of held from the last slice\n"
                 "  -q, --quiet          no summary line\n"
                 "  -h, --help           this text\n"
                 "      --version        the version and the commit it was built from\n"
                 "The slices end short of grazing (θo_max = 0.99·90°·(N-1)/N for N default slices, 81.7° for\n"
                 "12): beyond θo_max, on the sphere's rim, the last slice's values (and, with --error, its\n"
                 "errors) are held as they are, and the summary line says how many pixels that is. Pixels\n"
                 "the LSS does not cover are magenta: no estimate within --max-gap of a light's direction,\n"
                 "a view angle below the first slice, and with --strict the rim beyond the last slice.\n"
                 "Exit status: 0 success, 2 bad input or flags, 1 other failure.\n");
}

[[noreturn]] void die(int code, const char *fmt, const char *a = "", const char *b = "")
{
    std::fprintf(stderr, "lssview: ");
    std::fprintf(stderr, fmt, a, b);
    std::fprintf(stderr, "\n");
    std::exit(code);
}

double parse_num(const char *flag, const char *v, double lo, double hi)
{
    char *end = nullptr;
    errno = 0;
    double x = std::strtod(v, &end);
    if (end == v || *end || errno || !std::isfinite(x) || x < lo || x > hi) {
        char range[96];
        std::snprintf(range, sizeof range, "%s: '%%s' is not a number in [%g, %g]", flag, lo, hi);
        die(2, range, v);
    }
    return x;
}

Options parse_args(int argc, char **argv)
{
    Options o;
    bool lights_given = false;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        std::string val;
        bool has_eq = false;
        if (a.size() > 2 && a[0] == '-' && a.find('=') != std::string::npos) {
            val = a.substr(a.find('=') + 1);
            a = a.substr(0, a.find('='));
            has_eq = true;
        }
        auto need = [&]() -> std::string {
            if (has_eq) return val;
            if (i + 1 >= argc) die(2, "%s needs a value (see --help)", a.c_str());
            return argv[++i];
        };
        if (a == "-h" || a == "--help") {
            usage(stdout);
            std::exit(0);
        } else if (a == "--version") {
            std::printf("lssview %s\n", lsqt_version());
            std::exit(0);
        } else if (a == "-o" || a == "--output") {
            o.out = need();
        } else if (a == "--image-dim") {
            std::string v = need();
            double d = parse_num("--image-dim", v.c_str(), 16, 8192);
            if (d != std::floor(d)) die(2, "--image-dim: '%s' is not a whole number", v.c_str());
            o.dim = (int)d;
        } else if (a == "--image-mul") {
            std::string v = need();
            o.mul = parse_num("--image-mul", v.c_str(), 0, 1e30);
        } else if (a == "--error") {
            o.error = true;
        } else if (a == "--error-max") {
            std::string v = need();
            o.error_max = parse_num("--error-max", v.c_str(), 1e-12, 1e12);
        } else if (a == "--max-gap") {
            std::string v = need();
            o.max_gap_deg = parse_num("--max-gap", v.c_str(), 0.01, 180);
        } else if (a == "--light") {
            std::string v = need();
            double c[4];
            char tail = 0;
            if (std::sscanf(v.c_str(), "%lf,%lf,%lf,%lf%c", &c[0], &c[1], &c[2], &c[3], &tail) != 4)
                die(2, "--light: '%s' is not X,Y,Z,E", v.c_str());
            glm::dvec3 d(c[0], c[1], c[2]);
            double len = glm::length(d);
            if (!std::isfinite(len) || len <= 0 || !std::isfinite(c[3]) || c[3] < 0)
                die(2, "--light: '%s' needs a nonzero direction and E >= 0", v.c_str());
            if (!lights_given) o.lights.clear();
            lights_given = true;
            o.lights.push_back({d / len, c[3]});
        } else if (a == "--channel") {
            std::string v = need();
            double k = parse_num("--channel", v.c_str(), 0, 1e6);
            if (k != std::floor(k)) die(2, "--channel: '%s' is not a whole number", v.c_str());
            o.channel = (int)k;
        } else if (a == "--strict") {
            o.strict = true;
        } else if (a == "-q" || a == "--quiet") {
            o.quiet = true;
        } else if (a.size() > 1 && a[0] == '-') {
            die(2, "unknown option '%s' (see --help)", argv[i]);
        } else {
            if (!o.in.empty()) die(2, "more than one input ('%s' and '%s')", o.in.c_str(), argv[i]);
            o.in = argv[i];
        }
    }
    if (o.in.empty()) {
        usage(stderr);
        std::exit(2);
    }
    if (!lights_given) {
        o.lights = {{glm::normalize(glm::dvec3(-1, 1, 1.2)), 2.5},
                    {glm::normalize(glm::dvec3(1, 0.2, 0.6)), 0.8},
                    {glm::normalize(glm::dvec3(0, 1, -0.3)), 1.2}};
    }
    if (o.out.empty()) o.out = o.in + (o.error ? ".error.png" : ".png");
    return o;
}

// What the picture shows of a run's bands: nb of them from band b0 (one: grey), their
// wavelengths (empty: R, G, B, or one band) and their weights y in the luminance Y (what
// --error shows with bands), and a phrase for the summary line ("" for one band).
struct Colour {
    int b0 = 0, nb = 0; // nb 0: refused, err says why
    std::vector<double> wl, y;
    std::string what;
};

Colour colour_of(const lsqt_state &st, const Options &o, char *err, size_t cap)
{
    Colour c;
    const int n = lsqt_state_bands(&st);
    char lab[32], buf[160];
    if (o.channel >= n) {
        if (n == 1) std::snprintf(err, cap, "--channel %d: '%s' has one band: K must be 0", o.channel, o.in.c_str());
        else std::snprintf(err, cap, "--channel %d: '%s' has %d bands: K must be 0 to %d", o.channel, o.in.c_str(), n, n - 1);
        return c;
    }
    c.nb = 1, c.y = {1.0};
    if (n == 1) return c;
    if (o.channel >= 0) {
        c.b0 = o.channel;
        std::snprintf(buf, sizeof buf, "band %d (%s) of %d in grey (--channel)", o.channel,
                      lsqt_band_label_one(n, st.wavelengths, o.channel, lab, sizeof lab), n);
        c.what = buf;
        return c;
    }
    if (!st.wavelengths && n != 3) {
        std::snprintf(err, cap, "'%s' has %d bands without wavelengths, which make no colour: choose one with --channel K "
                      "(0 to %d)", o.in.c_str(), n, n - 1);
        c.nb = 0;
        return c;
    }
    c.nb = n;
    if (!st.wavelengths) {
        c.y = {0.2126, 0.7152, 0.0722}; // Rec. 709 (sRGB) luminance
        c.what = o.error ? "bands R, G, B: the error of their luminance" : "colour from bands R, G, B";
        return c;
    }
    c.wl.assign(st.wavelengths, st.wavelengths + n);
    c.y.assign((size_t)n, 0.0);
    std::vector<double> unit((size_t)n, 0.0);
    for (int b = 0; b < n; b++) { // Y is linear in the spectrum: the weight of band b is Y of its unit spectrum
        double xyz[3] = {0, 0, 0};
        unit[(size_t)b] = 1;
        lsqt_spectrum_to_xyz(n, c.wl.data(), unit.data(), xyz);
        unit[(size_t)b] = 0;
        c.y[(size_t)b] = xyz[1];
    }
    std::snprintf(buf, sizeof buf, "%s %d wavelengths, %g to %g nm%s", o.error ? "bands at" : "colour from a spectrum at", n,
                  c.wl.front(), c.wl.back(), o.error ? ": the error of their luminance" : " (linear sRGB)");
    c.what = buf;
    return c;
}

// The slices from above, sorted by θo, each with its upper-hemisphere estimates and their
// mirror images: nb bands from band b0 on (est: band after band, lsqt_estimates). A
// direction whose value is not finite in a band is left out (in every band).
std::vector<Slice> build_slices(const lsqt_state &st, const lsqt_slice_est *est, int b0, int nb)
{
    std::vector<Slice> out;
    const size_t ns = (size_t)st.n_slices;
    for (int s = 0; s < st.n_slices; s++) {
        if (st.slice_flags && (st.slice_flags[s] & LSQT_SLICE_BELOW)) continue;
        Slice sl;
        sl.theta = st.theta_o[s];
        sl.s = std::sin(sl.theta);
        for (int k = 0; k < st.n_wi; k++) {
            const float *w = st.wi + ((size_t)s * (size_t)st.n_wi + (size_t)k) * 4;
            bool finite = true;
            for (int b = 0; b < nb; b++) finite = finite && std::isfinite(est[(size_t)(b0 + b) * ns + (size_t)s].f[k].mean);
            if (!(w[2] > 0) || !finite) continue;
            const size_t row = sl.f.size() / (size_t)nb;
            for (int b = 0; b < nb; b++) {
                const lsqt_est &q = est[(size_t)(b0 + b) * ns + (size_t)s].f[k];
                sl.f.push_back(q.mean);
                sl.e.push_back(q.err);
            }
            glm::dvec3 d = glm::normalize(glm::dvec3(w[0], w[1], w[2]));
            sl.pts.push_back({d, row});
            if (d.y > 1e-7) sl.pts.push_back({glm::dvec3(d.x, -d.y, d.z), row});
        }
        out.push_back(std::move(sl));
    }
    std::sort(out.begin(), out.end(), [](const Slice &a, const Slice &b) { return a.theta < b.theta; });
    return out;
}

struct Eval {
    bool ok;
    bool held = false; // θo beyond the last slice, the last slice's values held
};

// Scattered-data interpolation within one slice (see the top of the file): f and e, nb
// bands each, with the same weights in every band. False where no estimate is near.
bool eval_slice(const Slice &sl, const glm::dvec3 &q, double rmax_chord, int nb, double *f, double *e)
{
    double dist[K_NEAR + 1];
    int idx[K_NEAR + 1];
    int n = 0;
    const size_t np = sl.pts.size();
    for (size_t j = 0; j < np; j++) {
        glm::dvec3 v = sl.pts[j].d - q;
        double d2 = glm::dot(v, v);
        if (n == K_NEAR + 1 && d2 >= dist[K_NEAR]) continue;
        int p = n < K_NEAR + 1 ? n++ : K_NEAR;
        while (p > 0 && dist[p - 1] > d2) {
            dist[p] = dist[p - 1];
            idx[p] = idx[p - 1];
            p--;
        }
        dist[p] = d2;
        idx[p] = (int)j;
    }
    double R2 = rmax_chord * rmax_chord;
    if (n == K_NEAR + 1 && dist[K_NEAR] < R2) R2 = dist[K_NEAR];
    double sw = 0, w[K_NEAR];
    int m = 0;
    for (; m < n && m < K_NEAR; m++) {
        if (dist[m] >= R2) break;
        double u = 1.0 - dist[m] / R2;
        w[m] = u * u;
        sw += w[m];
    }
    if (!(sw > 0)) return false;
    for (int b = 0; b < nb; b++) {
        double sf = 0, se = 0;
        for (int k = 0; k < m; k++) {
            const size_t at = sl.pts[(size_t)idx[k]].row * (size_t)nb + (size_t)b;
            sf += w[k] * sl.f[at];
            se += w[k] * sl.e[at];
        }
        f[b] = sf / sw, e[b] = se / sw;
    }
    return true;
}

// wi (slice frame of θo) carried to the frame of a slice at sin θ_k = sk.
glm::dvec3 warp(const glm::dvec3 &wi, double s, double sk)
{
    double c = (s - sk) / (1.0 - s * sk);
    if (c == 0) return wi;
    // (p + c) / (1 + c p), p = x + i y
    double nr = wi.x + c, ni = wi.y;
    double dr = 1.0 + c * wi.x, di = c * wi.y;
    double den = dr * dr + di * di;
    double x = (nr * dr + ni * di) / den, y = (ni * dr - nr * di) / den;
    double z2 = 1.0 - x * x - y * y;
    return glm::dvec3(x, y, z2 > 0 ? std::sqrt(z2) : 0.0);
}

struct Renderer {
    const std::vector<Slice> &slices;
    const std::vector<Light> &lights;
    double rmax_chord;
    bool strict;
    int nb; // bands in the slices' values

    // θo beyond the last slice, where the last slice is held (not with --strict)
    bool held(double theta_o) const { return !strict && !slices.empty() && theta_o > slices.back().theta; }
    // θo within the slices' range or held
    bool in_range(double theta_o) const
    {
        return !slices.empty() && theta_o >= slices.front().theta && (theta_o <= slices.back().theta || held(theta_o));
    }

    // f and its error (nb bands each) at (θo, wi in the frame where wo = (sin θo, 0, cos θo));
    // tmp: 4 nb doubles of scratch. False where not covered.
    bool f(double theta_o, const glm::dvec3 &wi, double *fv, double *ev, double *tmp) const
    {
        if (!in_range(theta_o)) return false;
        if (held(theta_o)) return eval_slice(slices.back(), wi, rmax_chord, nb, fv, ev); // as it is, no warp
        size_t b = 0;
        while (b + 1 < slices.size() && slices[b + 1].theta < theta_o) b++;
        // slices[b].theta <= theta_o; the upper neighbour, if theta_o is not on slice b
        if (slices[b].theta == theta_o || b + 1 == slices.size()) {
            if (slices[b].theta != theta_o) return false;
            return eval_slice(slices[b], wi, rmax_chord, nb, fv, ev);
        }
        const Slice &A = slices[b], &B = slices[b + 1];
        double t = (theta_o - A.theta) / (B.theta - A.theta);
        double s = std::sin(theta_o);
        double *af = tmp, *ae = tmp + nb, *bf = tmp + 2 * nb, *be = tmp + 3 * nb;
        if (!eval_slice(A, warp(wi, s, A.s), rmax_chord, nb, af, ae) ||
            !eval_slice(B, warp(wi, s, B.s), rmax_chord, nb, bf, be))
            return false;
        for (int k = 0; k < nb; k++) fv[k] = (1 - t) * af[k] + t * bf[k], ev[k] = (1 - t) * ae[k] + t * be[k];
        return true;
    }

    // value and error (nb bands each) of the pixel with normal n; ok false when uncovered.
    // tmp: 6 nb doubles of scratch.
    Eval pixel(const glm::dvec3 &n, double *v, double *e, double *tmp) const
    {
        const glm::dvec3 V(0, 0, 1);
        double cos_o = std::min(1.0, std::max(-1.0, n.z));
        double theta_o = std::acos(cos_o);
        glm::dvec3 t = V - cos_o * n;
        double tl = glm::length(t);
        t = tl > 1e-12 ? t / tl : glm::normalize(glm::dvec3(1, 0, 0) - n.x * n);
        glm::dvec3 b = glm::cross(n, t);
        double *fv = tmp, *fe = tmp + nb;
        for (int k = 0; k < nb; k++) v[k] = 0, e[k] = 0;
        for (const Light &L : lights) {
            double ci = glm::dot(L.dir, n);
            if (ci <= 0 || L.E == 0) continue;
            glm::dvec3 wi(glm::dot(L.dir, t), glm::dot(L.dir, b), ci);
            if (!f(theta_o, wi, fv, fe, tmp + 2 * nb)) return {false};
            for (int k = 0; k < nb; k++) {
                v[k] += L.E * ci * fv[k];
                e[k] += L.E * ci * fe[k];
            }
        }
        if (!in_range(theta_o)) return {false};
        return {true, held(theta_o)};
    }
};

// A 3x5 pixel font for the colour bar's labels.
const char *glyph(char c)
{
    switch (c) {
    case '0': return "111101101101111";
    case '1': return "010110010010111";
    case '2': return "111001111100111";
    case '3': return "111001111001111";
    case '4': return "101101111001001";
    case '5': return "111100111001111";
    case '6': return "111100111101111";
    case '7': return "111001001001001";
    case '8': return "111101111101111";
    case '9': return "111101111001111";
    case '.': return "000000000000010";
    case '%': return "101001010100101";
    case 'e': return "000111111100111";
    case '-': return "000000111000000";
    case '+': return "000010111010000";
    default: return "000000000000000";
    }
}

void draw_text(std::vector<float> &img, int W, int H, int x0, int y0, int scale, const std::string &s)
{
    for (size_t k = 0; k < s.size(); k++) {
        const char *g = glyph(s[k]);
        for (int gy = 0; gy < 5; gy++)
            for (int gx = 0; gx < 3; gx++) {
                if (g[gy * 3 + gx] != '1') continue;
                for (int dy = 0; dy < scale; dy++)
                    for (int dx = 0; dx < scale; dx++) {
                        int x = x0 + ((int)k * 4 + gx) * scale + dx, y = y0 + gy * scale + dy;
                        if (x < 0 || y < 0 || x >= W || y >= H) continue;
                        for (int c = 0; c < 3; c++) img[((size_t)y * (size_t)W + (size_t)x) * 3 + (size_t)c] = 1.0f;
                    }
            }
    }
}

// False colour for u in [0, 1]: dark blue, blue, green, yellow, red.
glm::dvec3 false_colour(double u)
{
    static const glm::dvec3 stops[] = {{0.05, 0.05, 0.35}, {0.1, 0.35, 0.9}, {0.1, 0.75, 0.3}, {0.95, 0.9, 0.1},
                                       {0.9, 0.1, 0.05}};
    u = std::min(1.0, std::max(0.0, u)) * 4.0;
    int i = std::min(3, (int)u);
    return glm::mix(stops[i], stops[i + 1], u - i);
}

double nice_ceil(double x)
{
    if (!(x > 0)) return 1.0;
    double p = std::pow(10.0, std::floor(std::log10(x)));
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (m * p >= x * (1 - 1e-12)) return m * p;
    return 10 * p;
}

std::string percent_label(double v)
{
    char b[32];
    std::snprintf(b, sizeof b, "%.3g%%", v * 100);
    return b;
}

bool is_linear_format(const std::string &path)
{
    std::string ext = path.substr(path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
    for (char &c : ext) c = (char)std::tolower((unsigned char)c);
    return ext == ".exr" || ext == ".hdr" || ext == ".pfm";
}

double srgb(double v)
{
    v = std::min(1.0, std::max(0.0, v));
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}

} // namespace

int main(int argc, char **argv)
{
    Options o = parse_args(argc, argv);

    lsqt_state st;
    std::memset(&st, 0, sizeof st);
    char err[3 * LSQT_PATH_CAP];
    // The image goes where lsqt-cl's outputs go (util.h): never over the input, checked
    // before any work, written to a temporary beside it and renamed into place.
    if (o.in != "-" && lsqt_same_file(o.out.c_str(), o.in.c_str()))
        die(2, "the output '%s' would replace the input", o.out.c_str());
    if (lsqt_out_check(o.out.c_str(), err, sizeof err)) die(1, "%s", err);
    if (!OIIO::ImageOutput::create(o.out))
        die(2, "cannot write '%s': OpenImageIO has no writer for its extension (use .png, .exr, .hdr, .tif, ...)",
            o.out.c_str());
    if (lsqt_lss_read(o.in.c_str(), &st, err, sizeof err)) die(2, "%s", err);
    if (st.stage != LSQT_STAGE_RUN) {
        lsqt_state_free(&st);
        die(2, "%s: an RRSS pilot shard, not a run's state (merge the shards first)", o.in.c_str());
    }
    if (st.paths == 0) {
        lsqt_state_free(&st);
        die(2, "%s: holds no paths", o.in.c_str());
    }
    // The bands: one in grey (one band, or --channel K), or all of them in colour.
    const Colour cl = colour_of(st, o, err, sizeof err);
    if (!cl.nb) {
        lsqt_state_free(&st);
        die(2, "%s", err);
    }
    lsqt_slice_est *est = lsqt_estimates(&st);
    if (!est) {
        lsqt_state_free(&st);
        die(1, "out of memory");
    }
    if (o.error && st.paths < LSQT_MIN_ERR_PATHS) {
        char msg[64];
        std::snprintf(msg, sizeof msg, "%llu", (unsigned long long)LSQT_MIN_ERR_PATHS);
        die(2, "%s holds too few paths per slice for error bars (at least %s are needed)", o.in.c_str(), msg);
    }
    std::vector<Slice> slices = build_slices(st, est, cl.b0, cl.nb);
    lsqt_estimates_free(est, st.n_slices);
    lsqt_state_free(&st);
    if (slices.size() < 2 && !o.quiet)
        std::fprintf(stderr, "lssview: warning: fewer than two slices from above: only θo = θ_0 is estimated%s\n",
                     o.strict ? "" : " (held beyond it; --strict shows that magenta)");

    const double gap = o.max_gap_deg * M_PI / 180.0;
    const int nb = cl.nb;
    Renderer r{slices, o.lights, 2.0 * std::sin(std::min(gap, M_PI) / 2.0), o.strict, nb};
    const int D = o.dim;
    const bool linear = is_linear_format(o.out);
    // val: the pixel's value (with bands, its luminance Y), rel: its relative error; the
    // picture's pixels are written as they are rendered (no colour buffer of doubles)
    std::vector<double> val((size_t)D * D, 0.0), rel((size_t)D * D, 0.0);
    std::vector<unsigned char> kind((size_t)D * D, 0); // 0 outside, 1 value, 2 uncovered, 3 held value
    std::vector<float> img;
    if (!o.error) img.assign((size_t)D * D * 3, 0.0f);
    const double rad = SPHERE_FRAC * D;
    auto rows = [&](int j0, int j1) {
        std::vector<double> buf((size_t)8 * (size_t)nb); // values, errors, the renderer's scratch
        double *v = buf.data(), *e = v + nb, *tmp = v + 2 * nb;
        for (int j = j0; j < j1; j++)
            for (int i = 0; i < D; i++) {
                double x = (i + 0.5 - D / 2.0) / rad, y = (D / 2.0 - j - 0.5) / rad;
                double r2 = x * x + y * y;
                if (r2 >= 1) continue;
                size_t p = (size_t)j * (size_t)D + (size_t)i;
                Eval ev = r.pixel(glm::dvec3(x, y, std::sqrt(1 - r2)), v, e, tmp);
                if (!ev.ok) {
                    kind[p] = 2;
                    continue;
                }
                kind[p] = ev.held ? 3 : 1;
                double f = v[0], fe = e[0];
                if (nb > 1) { // bands: errors fully correlated between them too (an upper bound)
                    f = fe = 0;
                    for (int b = 0; b < nb; b++) f += cl.y[(size_t)b] * v[b], fe += cl.y[(size_t)b] * e[b];
                }
                val[p] = f;
                rel[p] = f > 0 ? fe / f : (fe > 0 ? INFINITY : 0.0);
                if (o.error) continue;
                double rgb[3] = {v[0], v[0], v[0]};
                if (cl.wl.empty() && nb == 3) rgb[1] = v[1], rgb[2] = v[2];
                else if (nb > 1 && lsqt_spectrum_to_srgb(nb, cl.wl.data(), v, rgb)) rgb[0] = rgb[1] = rgb[2] = NAN;
                for (int c = 0; c < 3; c++) {
                    double m = rgb[c] * o.mul; // linear formats: linear sRGB, unclamped
                    img[p * 3 + (size_t)c] = (float)(linear ? m : srgb(1.0 - std::exp(-std::max(0.0, m))));
                }
            }
    };
    unsigned nt = std::max(1u, std::min(16u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < nt; t++) pool.emplace_back(rows, (int)(D * (long)t / nt), (int)(D * (long)(t + 1) / nt));
    for (auto &th : pool) th.join();

    size_t n_unc = (size_t)std::count(kind.begin(), kind.end(), (unsigned char)2);
    size_t n_held = (size_t)std::count(kind.begin(), kind.end(), (unsigned char)3);
    auto has_value = [&](size_t p) { return kind[p] == 1 || kind[p] == 3; };
    int W = D;
    double emax = o.error_max;
    std::vector<double> errs;
    if (!o.error) {
        for (size_t p = 0; p < val.size(); p++)
            if (kind[p] == 2) img[p * 3] = 1, img[p * 3 + 1] = 0, img[p * 3 + 2] = 1;
    } else {
        for (size_t p = 0; p < val.size(); p++)
            if (has_value(p) && val[p] > 0 && std::isfinite(rel[p])) errs.push_back(rel[p]);
        if (emax == 0) emax = nice_ceil(errs.empty() ? 0.0 : *std::max_element(errs.begin(), errs.end()));
        int bar = std::max(40, D / 6);
        W = D + bar;
        img.assign((size_t)W * D * 3, 0.0f);
        for (int j = 0; j < D; j++)
            for (int i = 0; i < D; i++) {
                size_t p = (size_t)j * (size_t)D + (size_t)i;
                float *px = &img[((size_t)j * (size_t)W + (size_t)i) * 3];
                glm::dvec3 c(0);
                if (kind[p] == 2) c = glm::dvec3(1, 0, 1);
                else if (has_value(p) && val[p] > 0) c = false_colour(rel[p] / emax);
                else if (has_value(p)) c = glm::dvec3(0.3); // no light reaches it: no relative error
                px[0] = (float)c.x, px[1] = (float)c.y, px[2] = (float)c.z;
            }
        // the bar: bottom 0, top emax, with labels at 0, emax/2, emax
        int scale = std::max(1, D / 170);
        int top = D / 10, bottom = D - D / 10, x0 = D + bar / 8, x1 = D + bar / 8 + bar / 4;
        for (int y = top; y <= bottom; y++) {
            glm::dvec3 c = false_colour((double)(bottom - y) / (bottom - top));
            for (int x = x0; x < x1; x++) {
                float *px = &img[((size_t)y * (size_t)W + (size_t)x) * 3];
                px[0] = (float)c.x, px[1] = (float)c.y, px[2] = (float)c.z;
            }
        }
        for (int k = 0; k <= 2; k++) {
            int y = bottom - (bottom - top) * k / 2;
            draw_text(img, W, D, x1 + 2 * scale, y - 2 * scale, scale, percent_label(emax * k / 2.0));
        }
    }

    lsqt_out w;
    if (lsqt_out_open_named(&w, o.out.c_str(), err, sizeof err)) die(1, "%s", err);
    const std::string name = lsqt_out_name(&w);
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(name);
    if (!out) {
        lsqt_out_abort(&w);
        die(2, "cannot write '%s': %s", o.out.c_str(), OIIO::geterror().c_str());
    }
    OIIO::ImageSpec spec(W, D, 3, linear ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", linear && !o.error ? "Linear" : "sRGB");
    const double theta_max_deg = slices.empty() ? 0.0 : slices.back().theta * 180.0 / M_PI;
    char rim[160] = "";
    if (n_held > 0)
        std::snprintf(rim, sizeof rim, "; rim beyond theta_o %.1f deg held from the last slice", theta_max_deg);
    else if (o.strict)
        std::snprintf(rim, sizeof rim, "; --strict: rim beyond theta_o %.1f deg not covered", theta_max_deg);
    spec.attribute("ImageDescription",
                   std::string(o.error ? "lssview --error: relative standard error, " : "lssview: BSDF sphere, ") +
                       (cl.what.empty() ? "" : cl.what + ", ") + "magenta: not covered" + rim);
    if (!out->open(name, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, img.data()) || !out->close()) {
        lsqt_out_abort(&w);
        die(1, "cannot write '%s': %s", o.out.c_str(), out->geterror().c_str());
    }
    out.reset();
    // Image writers may not see a failed write (a full disk leaves a short file behind
    // them): the file must read back whole before it replaces anything.
    if (w.how == LSQT_OUT_REPLACE) {
        std::vector<float> back((size_t)W * D * 3);
        auto in = OIIO::ImageInput::open(name);
        const bool whole = in && in->spec().width == W && in->spec().height == D &&
                           in->spec().nchannels == 3 && in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, back.data());
        if (in) in->close();
        if (!whole) {
            lsqt_out_abort(&w);
            die(1, "cannot write '%s': the image written does not read back whole (%s)", o.out.c_str(),
                errno == ENOSPC ? std::strerror(ENOSPC) : "a full disk?");
        }
    }
    if (lsqt_out_commit_named(&w, err, sizeof err)) die(1, "%s", err);

    if (!o.quiet) {
        size_t n_sphere = (size_t)std::count_if(kind.begin(), kind.end(), [](unsigned char k) { return k != 0; });
        std::printf("lssview: wrote %s (%dx%d), %zu of %zu sphere pixels not covered (magenta)", o.out.c_str(), W, D,
                    n_unc, n_sphere);
        if (n_held > 0)
            std::printf("; rim beyond θo %.1f° held from the last slice (%zu pixels, %.1f %% of sphere pixels); "
                        "--strict shows it magenta",
                        theta_max_deg, n_held, 100.0 * (double)n_held / (double)n_sphere);
        else if (o.strict && !slices.empty())
            std::printf(", the rim beyond θo %.1f° included (--strict)", theta_max_deg);
        if (!cl.what.empty()) std::printf("; %s", cl.what.c_str());
        std::printf("\n");
        if (o.error) {
            std::sort(errs.begin(), errs.end());
            auto q = [&](double p) { return errs.empty() ? NAN : errs[(size_t)(p * (double)(errs.size() - 1))]; };
            std::printf("relative error: median %.4g, 90th percentile %.4g, max %.4g over %zu pixels (bar 0 to %g)\n",
                        q(0.5), q(0.9), errs.empty() ? NAN : errs.back(), errs.size(), emax);
        }
    }
    return 0;
}
