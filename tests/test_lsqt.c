/* Unit tests of the LSQT parser, validator and assembly helpers (docs/guide.md, the LSQT
 * language; docs/design.md section 1): every rule, every error message, defaults, pruning,
 * canonical text, hash and build options. */
#include "check.h"
#include "lsqt/assembly.h"

#include <locale.h>
#include <stdlib.h>

#define NAME "t.lsqt"

static int parse(const char *text, lsqt_assembly *a, lsqt_diag *d)
{
    return lsqt_parse(text, strlen(text), NAME, NULL, 1, NULL, a, d);
}

static int has_note(const lsqt_diag *d, const char *part)
{
    for (int i = 0; i < d->n_notes; i++)
        if (strstr(d->notes[i], part))
            return 1;
    return 0;
}

/* Canonical text in a fresh buffer (the caller frees it). */
static char *canonical(const lsqt_assembly *a)
{
    size_t n = lsqt_assembly_canonical(a, NULL, 0);
    char *text = malloc(n + 1);
    if (text)
        lsqt_assembly_canonical(a, text, n + 1);
    return text;
}

/* ---- Errors: text, line, part of the message ---------------------------------------- */

/* Wrappers that put a line in context, with the line number it gets. */
#define MEDIUM1(x) "Medium " x "\nLayer z=0 Null\nMedium\n"                    /* line 1 */
#define LAYER2(x) "Medium\nLayer z=0 " x "\nMedium\n"                          /* line 2 */
#define MEDIUM3(x) "Medium\nLayer z=1 Null\nMedium " x "\nLayer z=0 Null\nMedium\n" /* line 3 */
#define PHASES "HenyeyGreensteinPhase, HenyeyGreenstein2Phase, RayleighPhase, SggxPhase, DrainePhase, TabulatedPhase"
#define BSDFS "NullBsdf, LambertianBsdf, MicrosurfaceLambertianBrdf, " \
    "MicrosurfaceDielectricBsdf, MicrosurfaceConductiveBrdf, OrenNayarDiffuseBrdf"

typedef struct bad_case {
    const char *text;
    int line;
    const char *msg;
} bad_case;

static const bad_case bad_cases[] = {
    /* structure */
    { "", 0, NAME ": error: no layers (the input has no Medium or Layer lines); expected" },
    { "# only a comment\n\n  \t\n", 0, "error: no layers" },
    { "Medium\n", 1, NAME ":1: error: no layers; expected a Layer line after the Medium on line 1" },
    { "Medium\nLayer z=0 Null", 2, "the input ends with a layer; expected a bottom Medium line" },
    { "Medium\nLayer z=0 Null\nMedium\nMedium\n", 4,
      "a Medium line where a Layer line belongs at 'Medium'; expected Layer here (lines "
      "alternate Medium, Layer, Medium, ..., Medium)" },
    { "Layer z=0 Null\nMedium\n", 1, "a Layer line where a Medium line belongs at 'Layer'" },
    { "Foo\n", 1, "unknown line name at 'Foo'; expected Medium here" },
    { "medium\n", 1, "unknown line name at 'medium'" },
    { "Medium\nlayer z=0 Null\nMedium\n", 2, "unknown line name at 'layer'; expected Layer" },
    { "eta=1\n", 1, "unknown line name at 'eta=1'" },
    /* Medium keys; unknown words are errors on Medium lines too (the original tool ignored them silently) */
    { MEDIUM1("foo"), 1,
      "unknown word at 'foo'; expected one of: eta mua mus or a phase model (" PHASES ")" },
    { MEDIUM1("eta=1.5 colour=red"), 1,
      "unknown key at 'colour=red'; expected one of: eta mua mus or a phase model (" PHASES ")" },
    { MEDIUM1("Eta=1"), 1, "unknown key at 'Eta=1'" },
    { MEDIUM1("z=1"), 1, "unknown key at 'z=1'; expected one of: eta mua mus or a phase "
      "model (" PHASES ") ('z' is a key of Layer)" },
    { MEDIUM1("eta"), 1, "missing '=' and value at 'eta'; expected eta=<number> in (0, 100]" },
    { MEDIUM1("eta="), 1, "missing value after '=' at 'eta='; expected eta=<number>" },
    { MEDIUM1("=1"), 1, "missing key name before '=' at '=1'; expected one of: eta mua mus" },
    { MEDIUM1("eta=1 eta=1"), 1,
      "repeated key at 'eta=1'; expected eta at most once (already given as 'eta=1')" },
    { MEDIUM1("eta=101"), 1, "value out of range at 'eta=101'; expected eta=<number> in (0, 100]" },
    { MEDIUM1("eta=0"), 1, "value out of range at 'eta=0'" },
    { MEDIUM1("eta=0.5"), 1, "eta below 1 at 'eta=0.5'; expected eta >= 1 (eta < 1 is "
      "allowed only for the metal below a MicrosurfaceConductiveBrdf)" },
    { "Medium\nLayer z=0 Lambertian fR=0.5 fT=0.5\nMedium eta=0.5\n", 3, "eta below 1 at 'eta=0.5'" },
    { MEDIUM1("mua=-1"), 1, "value out of range at 'mua=-1'; expected mua=<number> in [0, 1e+12]" },
    { MEDIUM1("mus=1e13 HenyeyGreenstein"), 1, "value out of range at 'mus=1e13'" },
    /* strict numbers */
    { MEDIUM1("eta=0.5x"), 1, "not a number at 'eta=0.5x'; expected eta=<number> in (0, 100]" },
    { MEDIUM1("eta=nan"), 1, "not a number at 'eta=nan'" },
    { MEDIUM1("eta=inf"), 1, "not a number at 'eta=inf'" },
    { MEDIUM1("eta=-infinity"), 1, "not a number at 'eta=-infinity'" },
    { MEDIUM1("eta=1e999"), 1, "number out of range at 'eta=1e999'" },
    { MEDIUM1("eta=0x1p3"), 1, "not a number at 'eta=0x1p3'" },
    { MEDIUM1("eta=0x10"), 1, "not a number at 'eta=0x10'" },
    { MEDIUM1("eta=1e"), 1, "not a number at 'eta=1e'" },
    { MEDIUM1("eta=e5"), 1, "not a number at 'eta=e5'" },
    { MEDIUM1("eta=."), 1, "not a number at 'eta=.'" },
    { MEDIUM1("eta=+"), 1, "not a number at 'eta=+'" },
    { MEDIUM1("eta=1..2"), 1, "not a number at 'eta=1..2'" },
    { MEDIUM1("eta=--1"), 1, "not a number at 'eta=--1'" },
    { MEDIUM1("eta=1=2"), 1, "not a number at 'eta=1=2'" },
    { MEDIUM1("eta=1,5"), 1, "a list of values in a run of one band at 'eta=1,5'" },
    { MEDIUM1("eta=1.00000000000000000000000000000000000000000000000000000000000000000000000000"
              "000000000000000000000000000000000000000000000000000000000000000000000000000000"
              "0000000000000"),
      1, "number too long at 'eta=1.000000" },
    /* top, bottom and scattering media */
    { "Medium mua=1\nLayer z=0 Null\nMedium\n", 1, "the top medium absorbs at 'mua=1'; expected "
      "mua=0 (the top and bottom media must neither absorb nor scatter, except the metal below "
      "a MicrosurfaceConductiveBrdf)" },
    { "Medium mus=1 HenyeyGreenstein\nLayer z=0 Null\nMedium\n", 1,
      "the top medium scatters at 'mus=1'; expected mus=0" },
    { "Medium\nLayer z=0 Null\nMedium mua=0.1\n", 3, "the bottom medium absorbs at 'mua=0.1'" },
    { "Medium\nLayer z=0 Lambertian fR=0 fT=0.5\nMedium mus=1 Rayleigh\n", 3,
      "the bottom medium scatters at 'mus=1'" },
    { MEDIUM3("mus=1"), 3, "scattering medium without a phase model at 'mus=1'; expected a "
      "phase model after the Medium keys when mus > 0: one of " PHASES },
    { MEDIUM3("mus=1 HenyeyGreenstein Rayleigh"), 3,
      "a second phase model at 'Rayleigh'; expected one of: g (keys of HenyeyGreensteinPhase)" },
    { MEDIUM3("mus=1 HenyeyGreenstein foo"), 3,
      "unknown word at 'foo'; expected one of: g (keys of HenyeyGreensteinPhase)" },
    { MEDIUM3("mus=1 HenyeyGreenstein g=0.1 eta=1.5"), 3, "unknown key at 'eta=1.5'; expected "
      "one of: g (keys of HenyeyGreensteinPhase) ('eta' is a key of Medium)" },
    { MEDIUM3("mus=1 HG"), 3, "unknown word at 'HG'" },
    { MEDIUM3("mus=1 henyeygreensteinphase"), 3, "unknown word at 'henyeygreensteinphase'" },
    /* phase keys */
    { MEDIUM3("mus=1 HenyeyGreensteinPhase g=1"), 3,
      "value out of range at 'g=1'; expected g=<number> in [-0.999999, 0.999999] (closer to +-1 the "
      "forward peak (1+|g|)/(4 pi (1-|g|)^2) would outgrow the tallies' range)" },
    /* the peak (1 + g) / (4 pi (1 - g)^2) at g = 1 - 1e-7 is 1.6e13, at the tallies' 2^44 */
    { MEDIUM3("mus=1 HenyeyGreensteinPhase g=0.9999999"), 3, "value out of range at 'g=0.9999999'" },
    { MEDIUM3("mus=1 HenyeyGreenstein2Phase g1=-0.9999999"), 3, "value out of range at 'g1=-0.9999999'" },
    /* a number that underflows is an error like one that overflows, not a silent 0 */
    { "Medium\nLayer z=0 LambertianBsdf fR=1e-400\nMedium\n", 2,
      "number too small (below 2.2e-308 it cannot be held; write 0 for zero) at 'fR=1e-400'" },
    { "Medium\nLayer z=0 LambertianBsdf fR=1e-310\nMedium\n", 2, "number too small" },
    { MEDIUM3("mus=1 HenyeyGreensteinPhase g=-1"), 3, "value out of range at 'g=-1'" },
    { MEDIUM3("mus=1 HenyeyGreensteinPhase g=0.1 g=0.2"), 3, "repeated key at 'g=0.2'" },
    { MEDIUM3("mus=1 HenyeyGreenstein2Phase b=1.5"), 3,
      "value out of range at 'b=1.5'; expected b=<number> in [0, 1]" },
    { MEDIUM3("mus=1 HenyeyGreenstein2Phase g0=1"), 3, "value out of range at 'g0=1'" },
    { MEDIUM3("mus=1 HenyeyGreenstein2Phase g1=-1"), 3, "value out of range at 'g1=-1'" },
    { MEDIUM3("mus=1 HenyeyGreenstein2Phase g=0"), 3,
      "unknown key at 'g=0'; expected one of: g0 g1 b (keys of HenyeyGreenstein2Phase) ('g' is "
      "a key of HenyeyGreensteinPhase)" },
    { MEDIUM3("mus=1 RayleighPhase rho=1.5"), 3,
      "value out of range at 'rho=1.5'; expected rho=<number> in [-1, 1]" },
    { MEDIUM3("mus=1 SggxPhase Apara=0"), 3,
      "value out of range at 'Apara=0'; expected Apara=<number> in (0, 1e+06]" },
    { MEDIUM3("mus=1 SggxPhase Aperp=-1"), 3, "value out of range at 'Aperp=-1'" },
    { MEDIUM3("mus=1 SggxPhase type=diffuse"), 3,
      "unknown value at 'type=diffuse'; expected type=Specular|Diffuse" },
    { MEDIUM3("mus=1 SggxPhase apara=1"), 3,
      "unknown key at 'apara=1'; expected one of: Apara Aperp type (keys of SggxPhase)" },
    /* Layer */
    { "Medium\nLayer Lambertian\nMedium\n", 2,
      "missing required key z at 'Layer'; expected z=<number> in [-1e+12, 1e+12] right after Layer" },
    { "Medium\nLayer\nMedium\n", 2, "missing required key z at 'Layer'" },
    { "Medium\nLayer z=0\nMedium\n", 2,
      "missing BSDF model at 'z=0'; expected a BSDF model after the Layer keys: one of " BSDFS },
    { LAYER2("fR=0.5 Lambertian"), 2, "unknown key at 'fR=0.5'; expected one of: z or a BSDF "
      "model (" BSDFS ") ('fR' is a key of LambertianBsdf)" },
    { LAYER2("Lambertian z=1"), 2, "unknown key at 'z=1'; expected one of: fR fT (keys of "
      "LambertianBsdf) ('z' is a key of Layer)" },
    { "Medium\nLayer z=abc Null\nMedium\n", 2, "not a number at 'z=abc'; expected z=<number>" },
    { "Medium\nLayer z=1e13 Null\nMedium\n", 2, "value out of range at 'z=1e13'" },
    { "Medium\nLayer z=1 z=0 Null\nMedium\n", 2, "repeated key at 'z=0'" },
    { "Medium\nLayer z=0 Null\nMedium\nLayer z=0 Null\nMedium\n", 4, "layer not below the "
      "previous one at 'z=0'; expected z < 0 (z of the layer on line 2; z decreases down the file)" },
    { "Medium\nLayer z=0 Null\nMedium\nLayer z=1 Null\nMedium\n", 4,
      "layer not below the previous one at 'z=1'" },
    { LAYER2("Lambertian Null"), 2, "a second BSDF model at 'Null'; expected one of: fR fT" },
    { LAYER2("Foo"), 2, "unknown word at 'Foo'; expected one of: z or a BSDF model (" BSDFS ")" },
    { LAYER2("lambertianbsdf"), 2, "unknown word at 'lambertianbsdf'" },
    { LAYER2("Null fR=1"), 2, "unknown key at 'fR=1'; expected nothing after NullBsdf (it has no keys)" },
    { LAYER2("Null x"), 2, "unknown word at 'x'; expected nothing after NullBsdf" },
    /* Lambertian */
    { LAYER2("Lambertian fR=-0.1"), 2, "value out of range at 'fR=-0.1'; expected fR=<number> in [0, 1]" },
    { LAYER2("Lambertian fT=1.1"), 2, "value out of range at 'fT=1.1'" },
    { LAYER2("Lambertian fR=0.7 fT=0.5"), 2, "fR + fT = 1.2 exceeds 1 at 'fT=0.5'; expected "
      "fR + fT <= 1 (fR=0.7, fT=0.5; the rest is absorbed)" },
    { LAYER2("Lambertian fT=0.5 fR=0.7"), 2, "fR + fT = 1.2 exceeds 1 at 'fR=0.7'" },
    { LAYER2("Lambertian fT=0.5"), 2, "fR + fT = 1.5 exceeds 1 at 'fT=0.5'" },
    { LAYER2("Lambertian fR=0.5 fR=0.5"), 2, "repeated key at 'fR=0.5'" },
    { LAYER2("Lambertian fr=0.5"), 2, "unknown key at 'fr=0.5'; expected one of: fR fT" },
    { LAYER2("Lambertian alpha=0.5"), 2,
      "unknown key at 'alpha=0.5'; expected one of: fR fT (keys of LambertianBsdf)" },
    /* microsurface Lambertian */
    { LAYER2("MicrosurfaceLambertian alpha=0"), 2,
      "value out of range at 'alpha=0'; expected alpha=<number> in (0, 100]" },
    { LAYER2("MicrosurfaceLambertian alpha=101"), 2, "value out of range at 'alpha=101'" },
    { LAYER2("MicrosurfaceLambertian alpha=-1"), 2, "value out of range at 'alpha=-1'" },
    { LAYER2("MicrosurfaceLambertian fR=0.6 fT=0.6"), 2, "fR + fT = 1.2 exceeds 1 at 'fT=0.6'" },
    { LAYER2("MicrosurfaceLambertian iter_count=0"), 2,
      "value out of range at 'iter_count=0'; expected iter_count=<integer> in [1, 128]" },
    { LAYER2("MicrosurfaceLambertian iter_count=129"), 2, "value out of range at 'iter_count=129'" },
    { LAYER2("MicrosurfaceLambertian iter_count=2.5"), 2,
      "not an integer at 'iter_count=2.5'; expected iter_count=<integer> in [1, 128]" },
    { LAYER2("MicrosurfaceLambertian iter_count=auto"), 2, "not a number at 'iter_count=auto'" },
    { LAYER2("MicrosurfaceLambertian use_multiple_scattering=yes"), 2, "unknown value at "
      "'use_multiple_scattering=yes'; expected use_multiple_scattering=false|true" },
    { LAYER2("MicrosurfaceLambertian use_multiple_scattering=True"), 2, "unknown value" },
    { LAYER2("MicrosurfaceLambertian use_multiple_scattering=1"), 2, "unknown value" },
    { LAYER2("MicrosurfaceLambertian use_multiple_scattering="), 2, "missing value after '='" },
    { LAYER2("MicrosurfaceLambertian kR=1"), 2, "unknown key at 'kR=1'; expected one of: alpha fR "
      "fT iter_count use_multiple_scattering (keys of MicrosurfaceLambertianBrdf)" },
    /* microsurface dielectric */
    { LAYER2("MicrosurfaceDielectric kR=1.5"), 2,
      "value out of range at 'kR=1.5'; expected kR=<number> in [0, 1]" },
    { LAYER2("MicrosurfaceDielectric kT=-0.1"), 2, "value out of range at 'kT=-0.1'" },
    { LAYER2("MicrosurfaceDielectric fR=1"), 2, "unknown key at 'fR=1'" },
    /* microsurface conductive and its metal */
    { "Medium\nLayer z=0 MicrosurfaceConductive\nMedium eta=0.2 mua=3 mus=1 HenyeyGreenstein\n", 3,
      "the metal below a MicrosurfaceConductiveBrdf scatters at 'mus=1'; expected mus=0" },
    { "Medium\nLayer z=0 MicrosurfaceConductive\nMedium eta=0 mua=3\n", 3,
      "value out of range at 'eta=0'; expected eta=<number> in (0, 100]" },
    { LAYER2("MicrosurfaceConductive kR=1"), 2,
      "unknown key at 'kR=1'; expected one of: alpha iter_count use_multiple_scattering" },
    { LAYER2("MicrosurfaceConductive alpha=200"), 2, "value out of range at 'alpha=200'" },
    /* Oren-Nayar */
    { LAYER2("OrenNayarDiffuse sigma=0.9"), 2,
      "value out of range at 'sigma=0.9'; expected sigma=<number> in [0, 0.8]" },
    { LAYER2("OrenNayarDiffuse sigma=-0.1"), 2, "value out of range at 'sigma=-0.1'" },
    { LAYER2("OrenNayarDiffuse fR=1.1"), 2, "value out of range at 'fR=1.1'" },
    { LAYER2("OrenNayarDiffuse fT=0"), 2,
      "unknown key at 'fT=0'; expected one of: fR sigma (keys of OrenNayarDiffuseBrdf)" },
    /* garbage */
    { "Medium\x01\n", 1, "invalid character at 'Medium?'; expected printable ASCII (byte 0x01" },
    { "Medium \x7f\n", 1, "invalid character at '?'" },
    { "Medium\nLayer z=0 Null\vx\nMedium\n", 2, "invalid character at 'Null?x'" },
    { "M\xc3\xa9" "dium\n", 1, "invalid character at 'M??dium'" },
    { "Medium eta=1\fLayer\n", 1, "invalid character" },
    /* pruned lines are still read and checked line by line */
    { "Medium\nLayer z=1 Lambertian\nMedium\nLayer z=0 Lambertian fR=2\nMedium\n", 4,
      "value out of range at 'fR=2'" },
    { "Medium\nLayer z=1 Lambertian\nMedium mus=1\nLayer z=0 Null\nMedium\n", 3,
      "scattering medium without a phase model" },
};

static void check_bad(const bad_case *c)
{
    lsqt_assembly a;
    lsqt_diag d;
    memset(&a, 0xab, sizeof a); /* must come back empty whatever it held */
    int rc = parse(c->text, &a, &d);
    char prefix[64];
    if (c->line)
        snprintf(prefix, sizeof prefix, NAME ":%d: error: ", c->line);
    else
        snprintf(prefix, sizeof prefix, NAME ": error: ");
    CHECK(rc == 2, "rc %d for [%s]", rc, c->text);
    CHECK(strstr(d.error, c->msg) != NULL, "message\n  [%s]\nlacks\n  [%s]", d.error, c->msg);
    CHECK(strncmp(d.error, prefix, strlen(prefix)) == 0, "[%s] does not start with [%s]", d.error,
          prefix);
    CHECK(strstr(d.error, "; expected ") != NULL, "no 'expected' in [%s]", d.error);
    CHECK(d.error_line == c->line, "line %d, want %d: [%s]", d.error_line, c->line, d.error);
    CHECK(strlen(d.error) < sizeof d.error - 1, "message may be cut: [%s]", d.error);
    CHECK(a.n_layers == 0 && a.layers == NULL && a.media == NULL && a.n_pruned_layers == 0,
          "output not empty after [%s]", c->text);
}

static void test_bad_inputs(void)
{
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++)
        check_bad(&bad_cases[i]);
}

/* Input with NUL bytes (length given), long tokens and long names. */
static void test_garbage(void)
{
    lsqt_assembly a;
    lsqt_diag d;
    static const char with_nul[] = "Medium\nLayer z=0 Null\nMedium eta=1\0 x\n";
    CHECK(lsqt_parse(with_nul, sizeof with_nul - 1, NAME, NULL, 1, NULL, &a, &d) == 2, "NUL accepted");
    CHECK(strstr(d.error, "invalid character at 'eta=1?'") && d.error_line == 3, "%s", d.error);

    /* a NUL inside a comment is ignored like the rest of the comment */
    static const char nul_comment[] = "Medium # \0 comment\nLayer z=0 Null\nMedium";
    CHECK(lsqt_parse(nul_comment, sizeof nul_comment - 1, NAME, NULL, 1, NULL, &a, &d) == 0, "%s", d.error);
    lsqt_assembly_free(&a);

    /* the text need not be NUL terminated: only len bytes are read */
    static const char sliced[] = "Medium\nLayer z=0 Null\nMediumXYZ";
    CHECK(lsqt_parse(sliced, sizeof sliced - 4, NAME, NULL, 1, NULL, &a, &d) == 0, "%s", d.error);
    lsqt_assembly_free(&a);

    char long_tok[600] = "Medium ";
    memset(long_tok + 7, 'x', 500);
    long_tok[507] = '\0';
    CHECK(parse(long_tok, &a, &d) == 2, "long word accepted");
    CHECK(strstr(d.error, "at 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx...'") != NULL, "%s", d.error);

    char long_name[3000];
    memset(long_name, 'n', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    CHECK(lsqt_parse("Foo", 3, long_name, NULL, 1, NULL, &a, &d) == 2, "bad input accepted");
    CHECK(strlen(d.error) < sizeof d.error, "message too long");
    CHECK(d.error_line == 1, "line %d", d.error_line);

    /* no diag and no name are allowed */
    CHECK(lsqt_parse("Foo", 3, NAME, NULL, 1, NULL, &a, NULL) == 2, "bad input accepted without diag");
    CHECK(lsqt_parse("Foo", 3, NULL, NULL, 1, NULL, &a, &d) == 2 && strncmp(d.error, "<input>:1:", 10) == 0,
          "%s", d.error);
    CHECK(lsqt_parse(NULL, 0, NAME, NULL, 1, NULL, &a, &d) == 2 && strstr(d.error, "no layers"), "%s", d.error);
    CHECK(lsqt_parse(NULL, 5, NAME, NULL, 1, NULL, &a, &d) == 2 && strstr(d.error, "error: no text"), "%s",
          d.error);
    CHECK(lsqt_parse("Medium\nLayer z=0 Null\nMedium", 26, NAME, NULL, 1, NULL, NULL, &d) == 2 &&
          strstr(d.error, "error: no assembly to fill"), "%s", d.error);
}

/* ---- Good inputs --------------------------------------------------------------------- */

static const char *const tutorial_lambertian =
    "Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n";
static const char *const tutorial_rough =
    "Medium\nLayer z=0 MicrosurfaceLambertianBrdf fR=0.6 alpha=2.4\nMedium\n";
static const char *const tutorial_dust =
    "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.2\n"
    "Layer z=0 LambertianBsdf fR=1 fT=0\nMedium\n";
/* the dusty dielectric substrate of the seed's figure 4 */
static const char *const tutorial_dusty_dielectric =
    "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=-0.2\n"
    "Layer z=0 MicrosurfaceDielectricBsdf alpha=0.1\nMedium eta=1.5\n"
    "Layer z=-1 LambertianBsdf fR=0.8 fT=0\nMedium\n";

/* Parses text that must be valid; returns 0 after a failed CHECK. */
static int parse_good(const char *text, lsqt_assembly *a, lsqt_diag *d)
{
    int rc = parse(text, a, d);
    CHECK(rc == 0, "[%s] rejected: %s", text, d->error);
    CHECK(d->error[0] == '\0' && d->error_line == 0, "error set on success: %s", d->error);
    return rc == 0;
}

static int is_vacuum(const lsqt_medium *m)
{
    return m->eta == 1 && m->mua == 0 && m->mus == 0 && m->phase.kind == LSQT_PHASE_NONE;
}

static void test_tutorials(void)
{
    lsqt_assembly a;
    lsqt_diag d;
    if (parse_good(tutorial_lambertian, &a, &d)) {
        CHECK(a.n_layers == 1 && a.n_pruned_layers == 0 && d.n_notes == 0, "%d", a.n_layers);
        CHECK(a.layers[0].kind == LSQT_BSDF_LAMBERTIAN, "kind %d", a.layers[0].kind);
        CHECK(a.layers[0].v[LSQT_LAMBERTIAN_fR] == 0.6 && a.layers[0].v[LSQT_LAMBERTIAN_fT] == 0 && a.layers[0].z == 0, "values");
        CHECK(a.layers[0].line == 2 && a.media[0].line == 1 && a.media[1].line == 3, "lines");
        CHECK(is_vacuum(&a.media[0]) && is_vacuum(&a.media[1]), "media");
        CHECK(!lsqt_assembly_transmits(&a), "fT=0 transmits");
        lsqt_assembly_free(&a);
    }
    if (parse_good(tutorial_rough, &a, &d)) {
        const lsqt_layer *l = &a.layers[0];
        CHECK(l->kind == LSQT_BSDF_MS_LAMBERTIAN && l->v[LSQT_MS_LAMBERTIAN_alpha] == 2.4 && l->v[LSQT_MS_LAMBERTIAN_fR] == 0.6 &&
                  l->v[LSQT_MS_LAMBERTIAN_fT] == 0,
              "values");
        CHECK(l->iter_count == 6 && l->multiple_scattering == 1, "%d %d", l->iter_count,
              l->multiple_scattering);
        lsqt_assembly_free(&a);
    }
    if (parse_good(tutorial_dust, &a, &d)) {
        CHECK(a.n_layers == 2 && d.n_notes == 0, "%d layers, %d notes", a.n_layers, d.n_notes);
        CHECK(a.layers[0].kind == LSQT_BSDF_NULL && a.layers[0].z == 1, "null layer");
        CHECK(a.media[1].mus == 1 && a.media[1].phase.kind == LSQT_PHASE_HG &&
              a.media[1].phase.v[LSQT_HG_g] == 0.2, "dust");
        CHECK(a.layers[1].v[LSQT_LAMBERTIAN_fR] == 1 && a.layers[1].v[LSQT_LAMBERTIAN_fT] == 0, "ground");
        lsqt_assembly_free(&a);
    }
    if (parse_good(tutorial_dusty_dielectric, &a, &d)) {
        CHECK(a.n_layers == 3 && a.n_pruned_layers == 0, "%d", a.n_layers);
        const lsqt_layer *l = &a.layers[1];
        CHECK(l->kind == LSQT_BSDF_MS_DIELECTRIC && l->v[LSQT_MS_DIELECTRIC_alpha] == 0.1 && l->v[LSQT_MS_DIELECTRIC_kR] == 1 &&
                  l->v[LSQT_MS_DIELECTRIC_kT] == 1 &&
              l->iter_count == 1 && l->multiple_scattering == 1, "dielectric");
        CHECK(a.media[2].eta == 1.5 && a.media[1].phase.v[LSQT_HG_g] == -0.2, "media");
        lsqt_assembly_free(&a);
    }
}

/* Each model alone with its defaults (docs/guide.md's table of models). */
static void test_bsdf_defaults(void)
{
    static const char *const names[] = {
        "NullBsdf", "LambertianBsdf", "MicrosurfaceLambertianBrdf", "MicrosurfaceDielectricBsdf",
        "MicrosurfaceConductiveBrdf", "OrenNayarDiffuseBrdf",
    };
    static const int kinds[] = {
        LSQT_BSDF_NULL, LSQT_BSDF_LAMBERTIAN, LSQT_BSDF_MS_LAMBERTIAN,
        LSQT_BSDF_MS_DIELECTRIC, LSQT_BSDF_MS_CONDUCTIVE, LSQT_BSDF_OREN_NAYAR,
    };
    for (int i = 0; i < 6; i++) {
        char text[128];
        lsqt_assembly a;
        lsqt_diag d;
        snprintf(text, sizeof text, "Medium\nLayer z=0 %s\nMedium\n", names[i]);
        if (!parse_good(text, &a, &d))
            continue;
        const lsqt_layer *l = &a.layers[0];
        CHECK(l->kind == kinds[i], "%s: kind %d", names[i], l->kind);
        CHECK(strcmp(lsqt_bsdf_name(kinds[i]), names[i]) == 0, "%s", lsqt_bsdf_name(kinds[i]));
        switch (kinds[i]) {
        case LSQT_BSDF_LAMBERTIAN:
            CHECK(l->v[LSQT_LAMBERTIAN_fR] == 1 && l->v[LSQT_LAMBERTIAN_fT] == 0, "Lambertian defaults");
            break;
        case LSQT_BSDF_MS_LAMBERTIAN:
            CHECK(l->v[LSQT_MS_LAMBERTIAN_alpha] == 0.5 && l->v[LSQT_MS_LAMBERTIAN_fR] == 1 && l->v[LSQT_MS_LAMBERTIAN_fT] == 0 &&
                  l->iter_count == 4 &&
                  l->multiple_scattering == 1, "microsurface Lambertian defaults");
            break;
        case LSQT_BSDF_MS_DIELECTRIC:
            CHECK(l->v[LSQT_MS_DIELECTRIC_alpha] == 0.5 && l->v[LSQT_MS_DIELECTRIC_kR] == 1 && l->v[LSQT_MS_DIELECTRIC_kT] == 1 &&
                  l->iter_count == 4 &&
                  l->multiple_scattering == 1, "microsurface dielectric defaults");
            break;
        case LSQT_BSDF_MS_CONDUCTIVE:
            CHECK(l->v[LSQT_MS_CONDUCTIVE_alpha] == 0.5 && l->iter_count == 4 && l->multiple_scattering == 0,
                  "microsurface conductive defaults");
            break;
        case LSQT_BSDF_OREN_NAYAR:
            CHECK(l->v[LSQT_OREN_NAYAR_fR] == 1 && l->v[LSQT_OREN_NAYAR_sigma] == 0.1, "Oren-Nayar defaults");
            break;
        default:
            break;
        }
        CHECK(is_vacuum(&a.media[0]) && is_vacuum(&a.media[1]), "Medium defaults");
        lsqt_assembly_free(&a);
    }
    CHECK(strcmp(lsqt_bsdf_name(99), "unknown BSDF") == 0, "%s", lsqt_bsdf_name(99));
}

static void test_phase_defaults(void)
{
    static const char *const names[] = {
        "HenyeyGreensteinPhase", "HenyeyGreenstein2Phase", "RayleighPhase", "SggxPhase", "DrainePhase",
    };
    for (int i = 0; i < 5; i++) {
        char text[160];
        lsqt_assembly a;
        lsqt_diag d;
        snprintf(text, sizeof text, MEDIUM3("mus=2 %s"), names[i]);
        if (!parse_good(text, &a, &d))
            continue;
        const lsqt_phase *p = &a.media[1].phase;
        CHECK(p->kind == i + 1, "%s: kind %d", names[i], p->kind);
        CHECK(strcmp(lsqt_phase_name(i + 1), names[i]) == 0, "%s", lsqt_phase_name(i + 1));
        if (p->kind == LSQT_PHASE_SGGX)
            CHECK(p->v[LSQT_SGGX_apara] == 1 && p->v[LSQT_SGGX_aperp] == 1 && p->v[LSQT_SGGX_type] == 0,
                  "SGGX defaults");
        else
            CHECK(p->v[0] == 0 && p->v[1] == 0 && p->v[2] == 0 && p->v[3] == 0, "zeros");
        CHECK(a.media[1].mus == 2 && a.media[1].eta == 1 && a.media[1].mua == 0, "medium");
        lsqt_assembly_free(&a);
    }
    CHECK(strcmp(lsqt_phase_name(LSQT_PHASE_NONE), "none") == 0, "none");
}

/* Every key of every model, set away from its default; keys in any order. */
static void test_every_key(void)
{
    lsqt_assembly a;
    lsqt_diag d;
    const char *text =
        "Medium eta=1.2\n"
        "Layer z=5 LambertianBsdf fT=0.25 fR=0.5\n"
        "Medium mus=3 mua=0.5 eta=1.3 HenyeyGreensteinPhase g=-0.5\n"
        "Layer z=4 MicrosurfaceLambertianBrdf use_multiple_scattering=false iter_count=9 "
        "fT=0.3 fR=0.6 alpha=0.05\n"
        "Medium mus=1 HenyeyGreenstein2Phase b=0.25 g1=-0.5 g0=0.75\n"
        "Layer z=3 MicrosurfaceDielectricBsdf alpha=0.15 kR=0.5 kT=0.75 iter_count=1e1 "
        "use_multiple_scattering=true\n"
        "Medium eta=1.5 mus=1 RayleighPhase rho=-1\n"
        "Layer z=2 NullBsdf\n"
        "Medium mus=1 SggxPhase Apara=0.5 Aperp=2 type=Diffuse\n"
        "Layer z=1 OrenNayarDiffuseBrdf sigma=0.8 fR=0\n"
        "Medium eta=2\n";
    if (!parse_good(text, &a, &d))
        return;
    CHECK(a.n_layers == 5 && a.n_pruned_layers == 0, "%d", a.n_layers);
    const lsqt_layer *L = a.layers;
    const lsqt_medium *M = a.media;
    CHECK(M[0].eta == 1.2, "top eta");
    CHECK(L[0].z == 5 && L[0].v[LSQT_LAMBERTIAN_fR] == 0.5 && L[0].v[LSQT_LAMBERTIAN_fT] == 0.25, "Lambertian");
    CHECK(M[1].eta == 1.3 && M[1].mua == 0.5 && M[1].mus == 3 && M[1].phase.v[LSQT_HG_g] == -0.5, "HG");
    CHECK(L[1].v[LSQT_MS_LAMBERTIAN_alpha] == 0.05 && L[1].v[LSQT_MS_LAMBERTIAN_fR] == 0.6 &&
          L[1].v[LSQT_MS_LAMBERTIAN_fT] == 0.3 && L[1].iter_count == 9 &&
          L[1].multiple_scattering == 0, "microsurface Lambertian");
    CHECK(M[2].phase.kind == LSQT_PHASE_HG2 && M[2].phase.v[LSQT_HG2_g0] == 0.75 && M[2].phase.v[LSQT_HG2_g1] == -0.5 &&
          M[2].phase.v[LSQT_HG2_b] == 0.25, "HG2");
    CHECK(L[2].v[LSQT_MS_DIELECTRIC_alpha] == 0.15 && L[2].v[LSQT_MS_DIELECTRIC_kR] == 0.5 &&
          L[2].v[LSQT_MS_DIELECTRIC_kT] == 0.75 && L[2].iter_count == 10 &&
          L[2].multiple_scattering == 1, "microsurface dielectric");
    CHECK(M[3].phase.kind == LSQT_PHASE_RAYLEIGH && M[3].phase.v[LSQT_RAYLEIGH_rho] == -1 && M[3].eta == 1.5,
          "Rayleigh");
    CHECK(M[4].phase.kind == LSQT_PHASE_SGGX && M[4].phase.v[LSQT_SGGX_apara] == 0.5 &&
          M[4].phase.v[LSQT_SGGX_aperp] == 2 && M[4].phase.v[LSQT_SGGX_type] == 1, "SGGX");
    CHECK(L[4].kind == LSQT_BSDF_OREN_NAYAR && L[4].v[LSQT_OREN_NAYAR_sigma] == 0.8 && L[4].v[LSQT_OREN_NAYAR_fR] == 0, "Oren-Nayar");
    /* the medium below Oren-Nayar cannot be reached: vacuum */
    CHECK(is_vacuum(&M[5]) && a.n_pruned_layers == 0, "bottom medium");
    CHECK(has_note(&d, NAME ":10: note: OrenNayarDiffuseBrdf transmits nothing: the medium on "
                   "line 11 cannot be reached and is modelled as vacuum"), "vacuum note missing");
    CHECK(has_note(&d, NAME ":8: note: NullBsdf between eta=1.5 and eta=1: light passes straight "
                   "on, without refraction"), "null note missing");
    lsqt_assembly_free(&a);

    /* the conductor: its metal has eta < 1 and absorbs */
    const char *metal = "Medium\nLayer z=0 MicrosurfaceConductiveBrdf alpha=0.3 iter_count=3 "
                        "use_multiple_scattering=true\nMedium eta=0.2 mua=3.1\n";
    if (parse_good(metal, &a, &d)) {
        CHECK(a.layers[0].v[LSQT_MS_CONDUCTIVE_alpha] == 0.3 && a.layers[0].iter_count == 3 &&
              a.layers[0].multiple_scattering == 1, "conductive");
        CHECK(a.media[1].eta == 0.2 && a.media[1].mua == 3.1 && d.n_notes == 0, "metal");
        lsqt_assembly_free(&a);
    }
}

/* Every alias gives the same assembly as the seed name. */
static void test_aliases(void)
{
    static const char *const pairs[][2] = {
        { "HenyeyGreensteinPhase g=0.3", "HenyeyGreenstein g=0.3" },
        { "HenyeyGreenstein2Phase b=0.3", "HenyeyGreenstein2 b=0.3" },
        { "RayleighPhase rho=0.3", "Rayleigh rho=0.3" },
        { "SggxPhase Apara=0.3", "Sggx Apara=0.3" },
    };
    static const char *const bsdf_pairs[][2] = {
        { "NullBsdf", "Null" },
        { "LambertianBsdf fR=0.3", "Lambertian fR=0.3" },
        { "MicrosurfaceLambertianBrdf alpha=0.3", "MicrosurfaceLambertian alpha=0.3" },
        { "MicrosurfaceDielectricBsdf alpha=0.3", "MicrosurfaceDielectric alpha=0.3" },
        { "MicrosurfaceConductiveBrdf alpha=0.3", "MicrosurfaceConductive alpha=0.3" },
        { "OrenNayarDiffuseBrdf sigma=0.3", "OrenNayarDiffuse sigma=0.3" },
    };
    for (int i = 0; i < 10; i++) {
        char t[2][200];
        lsqt_assembly a[2];
        lsqt_diag d;
        for (int k = 0; k < 2; k++) {
            if (i < 4)
                snprintf(t[k], sizeof t[k], MEDIUM3("mus=1 %s"), pairs[i][k]);
            else
                snprintf(t[k], sizeof t[k], LAYER2("%s"), bsdf_pairs[i - 4][k]);
        }
        if (parse_good(t[0], &a[0], &d) && parse_good(t[1], &a[1], &d)) {
            char *c0 = canonical(&a[0]), *c1 = canonical(&a[1]);
            CHECK(c0 && c1 && strcmp(c0, c1) == 0, "alias differs:\n%s\n%s", c0, c1);
            CHECK(lsqt_assembly_hash(&a[0]) == lsqt_assembly_hash(&a[1]), "alias hash differs");
            free(c0);
            free(c1);
            lsqt_assembly_free(&a[0]);
            lsqt_assembly_free(&a[1]);
        }
    }
}

/* Comments, blank lines, CRLF, tabs, a missing or doubled final newline change nothing. */
static void test_layout(void)
{
    static const char *const forms[] = {
        "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.2\n"
        "Layer z=0 LambertianBsdf fR=1 fT=0\nMedium",
        "Medium\r\nLayer z=1 NullBsdf\r\nMedium mus=1 HenyeyGreensteinPhase g=0.2\r\n"
        "Layer z=0 LambertianBsdf fR=1 fT=0\r\nMedium\r\n",
        "# dust on a white ground\n\nMedium   # vacuum\n\t Layer\tz=1 NullBsdf#top\n"
        "  Medium mus=1   HenyeyGreensteinPhase g=0.2  \n#\n\n"
        "Layer z=0 LambertianBsdf fT=0 fR=1\nMedium\n\n\n  \n",
        "Medium\n\nLayer z=1 Null\n\nMedium mus=1 HenyeyGreenstein g=0.2\n\n"
        "Layer z=0 Lambertian fR=1\n\nMedium\n\r\n",
    };
    lsqt_assembly ref;
    lsqt_diag d;
    if (!parse_good(tutorial_dust, &ref, &d))
        return;
    char *want = canonical(&ref);
    for (int i = 0; i < 4; i++) {
        lsqt_assembly a;
        if (!parse_good(forms[i], &a, &d))
            continue;
        char *got = canonical(&a);
        CHECK(got && want && strcmp(got, want) == 0, "form %d differs:\n%s", i, got);
        free(got);
        lsqt_assembly_free(&a);
    }
    /* lines are counted with blank and comment lines */
    lsqt_assembly a;
    if (parse_good(forms[2], &a, &d)) {
        CHECK(a.media[0].line == 3 && a.layers[0].line == 4 && a.media[1].line == 5 &&
              a.layers[1].line == 8 && a.media[2].line == 9, "line numbers");
        lsqt_assembly_free(&a);
    }
    CHECK(parse("#c\n\nMedium\n\nLayer z=0 Null\n\nMedium\n\nFoo\n", &a, &d) == 2 &&
          d.error_line == 9, "line %d: %s", d.error_line, d.error);
    free(want);
    lsqt_assembly_free(&ref);
}

static void test_numbers(void)
{
    static const struct {
        const char *text;
        double z;
    } good[] = {
        { "1e-3", 1e-3 }, { "+1", 1 }, { ".5", 0.5 }, { "5.", 5 }, { "1E2", 100 },
        { "-0.25", -0.25 }, { "-1e+3", -1000 }, { "007", 7 }, { "0e-999", 0 },
        { "1000000000000", 1e12 }, { "-1e12", -1e12 },
    };
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        char text[128];
        lsqt_assembly a;
        lsqt_diag d;
        snprintf(text, sizeof text, "Medium\nLayer z=%s Null\nMedium\n", good[i].text);
        if (parse_good(text, &a, &d)) {
            CHECK(a.layers[0].z == good[i].z, "z=%s read as %.17g", good[i].text, a.layers[0].z);
            lsqt_assembly_free(&a);
        }
    }
    /* a caller's locale does not change what parses, where such a locale exists */
    if (setlocale(LC_NUMERIC, "de_DE.UTF-8") || setlocale(LC_NUMERIC, "fr_FR.UTF-8")) {
        lsqt_assembly a;
        lsqt_diag d;
        if (parse_good("Medium\nLayer z=0.5 Null\nMedium\n", &a, &d)) {
            CHECK(a.layers[0].z == 0.5, "z read as %g under a comma locale", a.layers[0].z);
            lsqt_assembly_free(&a);
        }
        CHECK(parse("Medium\nLayer z=0,5 Null\nMedium\n", &a, &d) == 2, "comma accepted");
        setlocale(LC_NUMERIC, "C");
    }
}

static void test_iter_count_auto(void)
{
    static const struct {
        double alpha;
        int iter;
    } cases[] = {
        { 1e-4, 1 }, { 0.1, 1 }, { 0.10001, 2 }, { 0.2, 2 }, { 0.20001, 4 },
        { 0.5, 4 }, { 0.50001, 6 }, { 2.4, 6 }, { 100, 6 },
    };
    static const char *const models[] = {
        "MicrosurfaceLambertian", "MicrosurfaceDielectric", "MicrosurfaceConductive",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        for (int m = 0; m < 3; m++) {
            char text[128];
            lsqt_assembly a;
            lsqt_diag d;
            snprintf(text, sizeof text, LAYER2("%s alpha=%.17g"), models[m], cases[i].alpha);
            if (parse_good(text, &a, &d)) {
                CHECK(a.layers[0].iter_count == cases[i].iter, "alpha %g: iter_count %d, want %d",
                      cases[i].alpha, a.layers[0].iter_count, cases[i].iter);
                lsqt_assembly_free(&a);
            }
        }
    }
    lsqt_assembly a;
    lsqt_diag d;
    if (parse_good(LAYER2("MicrosurfaceLambertian alpha=0.05 iter_count=128"), &a, &d)) {
        CHECK(a.layers[0].iter_count == 128, "explicit iter_count %d", a.layers[0].iter_count);
        lsqt_assembly_free(&a);
    }
}

static void test_notes(void)
{
    lsqt_assembly a;
    lsqt_diag d;
    /* a phase model with mus=0 is read, then dropped */
    if (parse_good(MEDIUM3("eta=1.5 RayleighPhase rho=0.5"), &a, &d)) {
        CHECK(a.media[1].phase.kind == LSQT_PHASE_NONE && a.media[1].phase.v[LSQT_RAYLEIGH_rho] == 0, "phase kept");
        CHECK(has_note(&d, NAME ":3: note: RayleighPhase ignored: mus=0, the medium does not "
                       "scatter"), "phase note missing");
        char opts[256];
        lsqt_assembly_build_options(&a, opts, sizeof opts);
        CHECK(opts[0] == '\0', "options [%s]", opts);
        lsqt_assembly_free(&a);
    }
    /* NullBsdf between different eta: a note, not an error */
    if (parse_good("Medium\nLayer z=0 NullBsdf\nMedium eta=1.33\n", &a, &d)) {
        CHECK(d.n_notes == 1 && strcmp(d.notes[0], NAME ":2: note: NullBsdf between eta=1 and "
              "eta=1.33: light passes straight on, without refraction") == 0, "[%s]", d.notes[0]);
        lsqt_assembly_free(&a);
    }
    if (parse_good("Medium eta=1.33\nLayer z=0 NullBsdf\nMedium eta=1.33\n", &a, &d)) {
        CHECK(d.n_notes == 0, "%d notes", d.n_notes);
        lsqt_assembly_free(&a);
    }
    /* more notes than fit: the first ones are kept */
    char text[8192] = "Medium\n";
    for (int i = 0; i < 40; i++) {
        char line[64];
        /* eta alternates 2, 1, ..., 1: every Null layer separates different eta */
        snprintf(line, sizeof line, "Layer z=%d Null\nMedium eta=%d\n", -i, i % 2 ? 1 : 2);
        strcat(text, line);
    }
    if (parse_good(text, &a, &d)) {
        CHECK(d.n_notes == LSQT_DIAG_MAX_NOTES, "%d notes", d.n_notes);
        CHECK(a.n_layers == 40, "%d layers", a.n_layers);
        lsqt_assembly_free(&a);
    }
}

/* ---- Pruning --------------------------------------------------------------------------- */

static void test_pruning(void)
{
    lsqt_assembly a;
    lsqt_diag d;
    /* below Lambertian fT=0 nothing is reached; the unreachable bottom may even scatter */
    if (parse_good("Medium\nLayer z=1 Lambertian fT=0\nMedium mus=1 HenyeyGreenstein\n"
                   "Layer z=0 Lambertian\nMedium mua=1\n", &a, &d)) {
        CHECK(a.n_layers == 1 && a.n_pruned_layers == 1, "%d/%d", a.n_layers, a.n_pruned_layers);
        CHECK(is_vacuum(&a.media[1]) && a.media[1].line == 3, "bottom not vacuum");
        CHECK(has_note(&d, NAME ":2: note: LambertianBsdf transmits nothing: lines 3-5 cannot be "
                       "reached and are not modelled (1 layer pruned; the bottom medium is now "
                       "vacuum)"), "%s", d.n_notes ? d.notes[0] : "no note");
        char opts[256];
        lsqt_assembly_build_options(&a, opts, sizeof opts);
        CHECK(strcmp(opts, "-DLSQT_HAS_BSDF_LAMBERTIAN=1") == 0, "[%s]", opts);
        CHECK(!lsqt_assembly_transmits(&a), "transmits");
        lsqt_assembly_free(&a);
    }
    /* only the medium below is unreachable */
    if (parse_good("Medium\nLayer z=0 Lambertian\nMedium eta=1.5 mua=2\n", &a, &d)) {
        CHECK(a.n_layers == 1 && a.n_pruned_layers == 0 && is_vacuum(&a.media[1]), "vacuum");
        CHECK(has_note(&d, ":2: note: LambertianBsdf transmits nothing: the medium on line 3 "
                       "cannot be reached and is modelled as vacuum"), "note missing");
        lsqt_assembly_free(&a);
    }
    /* a conductor keeps its metal */
    if (parse_good("Medium\nLayer z=2 Null\nMedium eta=1.5\nLayer z=1 MicrosurfaceConductive\n"
                   "Medium eta=0.5 mua=2.5\nLayer z=0 Lambertian fR=0.5 fT=0.5\nMedium\n"
                   "Layer z=-1 Null\nMedium\n", &a, &d)) {
        CHECK(a.n_layers == 2 && a.n_pruned_layers == 2, "%d/%d", a.n_layers, a.n_pruned_layers);
        CHECK(a.media[2].eta == 0.5 && a.media[2].mua == 2.5 && a.media[2].line == 5, "metal");
        CHECK(has_note(&d, NAME ":4: note: MicrosurfaceConductiveBrdf transmits nothing: lines "
                       "6-9 cannot be reached and are not modelled (2 layers pruned; the metal on "
                       "line 5 is kept)"), "%s", d.n_notes ? d.notes[d.n_notes - 1] : "no note");
        lsqt_assembly_free(&a);
    }
    /* every kind of layer that transmits nothing, and near misses that transmit */
    static const struct {
        const char *bsdf;
        int pruned;
    } stops[] = {
        { "Lambertian fT=0", 1 }, { "Lambertian fR=0.5 fT=0.1", 0 },
        { "MicrosurfaceLambertian", 1 }, { "MicrosurfaceLambertian fR=0.5 fT=0.1", 0 },
        { "MicrosurfaceDielectric kT=0", 1 }, { "MicrosurfaceDielectric kT=0.01", 0 },
        { "OrenNayarDiffuse", 1 }, { "MicrosurfaceConductive", 1 }, { "Null", 0 },
    };
    for (size_t i = 0; i < sizeof stops / sizeof stops[0]; i++) {
        char text[256];
        snprintf(text, sizeof text, "Medium\nLayer z=1 %s\nMedium\nLayer z=0 Null\nMedium\n",
                 stops[i].bsdf);
        if (!parse_good(text, &a, &d))
            continue;
        CHECK(a.n_pruned_layers == stops[i].pruned && a.n_layers == 2 - stops[i].pruned,
              "%s: %d pruned", stops[i].bsdf, a.n_pruned_layers);
        CHECK(lsqt_assembly_transmits(&a) == !stops[i].pruned, "%s: transmits", stops[i].bsdf);
        CHECK(lsqt_layer_transmits(&a.layers[0]) == !stops[i].pruned, "%s", stops[i].bsdf);
        CHECK(has_note(&d, "transmits nothing") == stops[i].pruned, "%s: note", stops[i].bsdf);
        lsqt_assembly_free(&a);
    }
    /* the first stop counts; the conductor below it is pruned with the rest */
    if (parse_good("Medium\nLayer z=1 OrenNayarDiffuse\nMedium\nLayer z=0 MicrosurfaceConductive\n"
                   "Medium eta=0.3 mua=1\n", &a, &d)) {
        CHECK(a.n_layers == 1 && a.n_pruned_layers == 1 && is_vacuum(&a.media[1]), "pruned");
        lsqt_assembly_free(&a);
    }
}

/* ---- Canonical text, hash, build options --------------------------------------------- */

static const char *const good_inputs[] = {
    "Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n",
    "Medium\nLayer z=0 MicrosurfaceLambertianBrdf fR=0.6 alpha=2.4\nMedium\n",
    "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.2\n"
    "Layer z=0 LambertianBsdf fR=1 fT=0\nMedium\n",
    "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=-0.2\n"
    "Layer z=0 MicrosurfaceDielectricBsdf alpha=0.1\nMedium eta=1.5\n"
    "Layer z=-1 LambertianBsdf fR=0.8 fT=0\nMedium\n",
    "Medium eta=1.1\nLayer z=3 Null\nMedium mus=1e-3 mua=7 HenyeyGreenstein2 g0=0.3 g1=-0.1 b=0.1\n"
    "Layer z=2.5 MicrosurfaceDielectric kR=0.3 kT=0.7 use_multiple_scattering=false\n"
    "Medium eta=1.7 mus=5 Sggx Apara=0.1 Aperp=3 type=Diffuse\n"
    "Layer z=1e-7 MicrosurfaceLambertian alpha=1e-4 fR=0.2 fT=0.8\n"
    "Medium mus=2 Rayleigh rho=1\nLayer z=-1e6 MicrosurfaceConductive\nMedium eta=0.05 mua=4\n",
    "Medium\nLayer z=0 OrenNayarDiffuse fR=0.4 sigma=0.35\nMedium\n",
    "Medium\nLayer z=1 Lambertian fT=0\nMedium mus=1 HenyeyGreenstein\nLayer z=0 Null\nMedium\n",
    "Medium\nLayer z=-0 Null\nMedium eta=3 mus=0 HenyeyGreenstein g=0.5\n",
};

static void test_round_trip(void)
{
    for (size_t i = 0; i < sizeof good_inputs / sizeof good_inputs[0]; i++) {
        lsqt_assembly a, b;
        lsqt_diag d;
        if (!parse_good(good_inputs[i], &a, &d))
            continue;
        char *t1 = canonical(&a);
        if (t1 && parse_good(t1, &b, &d)) {
            char *t2 = canonical(&b);
            CHECK(t2 && strcmp(t1, t2) == 0, "round trip differs:\n%s---\n%s", t1, t2);
            CHECK(lsqt_assembly_hash(&a) == lsqt_assembly_hash(&b), "hash differs");
            CHECK(a.n_layers == b.n_layers && b.n_pruned_layers == 0, "layers");
            for (int k = 0; k < a.n_layers; k++) {
                const lsqt_layer *x = &a.layers[k], *y = &b.layers[k];
                CHECK(x->z == y->z && x->kind == y->kind && !memcmp(x->v, y->v, sizeof x->v) &&
                      x->iter_count == y->iter_count &&
                      x->multiple_scattering == y->multiple_scattering, "layer %d differs", k);
            }
            for (int k = 0; k <= a.n_layers; k++) {
                const lsqt_medium *x = &a.media[k], *y = &b.media[k];
                CHECK(x->eta == y->eta && x->mua == y->mua && x->mus == y->mus &&
                      memcmp(&x->phase, &y->phase, sizeof x->phase) == 0, "medium %d differs", k);
            }
            free(t2);
            lsqt_assembly_free(&b);
        }
        free(t1);
        lsqt_assembly_free(&a);
    }
}

static void test_canonical_text(void)
{
    lsqt_assembly a;
    lsqt_diag d;
    if (!parse_good("Medium\nLayer z=1 Null\nMedium mus=1 HenyeyGreenstein2 b=0.5\n"
                    "Layer z=0 MicrosurfaceLambertian fR=0.5 fT=0.1\nMedium\n", &a, &d))
        return;
    const char *want =
        "Medium eta=1 mua=0 mus=0\n"
        "Layer z=1 NullBsdf\n"
        "Medium eta=1 mua=0 mus=1 HenyeyGreenstein2Phase g0=0 g1=0 b=0.5\n"
        "Layer z=0 MicrosurfaceLambertianBrdf alpha=0.5 fR=0.5 fT=0.10000000000000001 "
        "iter_count=4 use_multiple_scattering=true\n"
        "Medium eta=1 mua=0 mus=0\n";
    char buf[1024];
    size_t n = lsqt_assembly_canonical(&a, buf, sizeof buf);
    CHECK(strcmp(buf, want) == 0, "canonical text:\n%s", buf);
    CHECK(n == strlen(want), "length %zu", n);
    /* like snprintf: the length needed, what fits, always terminated */
    char small[10];
    CHECK(lsqt_assembly_canonical(&a, small, sizeof small) == n && strcmp(small, "Medium et") == 0,
          "[%s]", small);
    CHECK(lsqt_assembly_canonical(&a, NULL, 0) == n, "size query");
    lsqt_assembly_free(&a);

    lsqt_assembly empty;
    memset(&empty, 0, sizeof empty);
    CHECK(lsqt_assembly_canonical(&empty, buf, sizeof buf) == 0 && buf[0] == '\0', "empty");
    CHECK(lsqt_assembly_build_options(&empty, buf, sizeof buf) == 0, "empty options");
    lsqt_assembly_free(&empty);
    lsqt_assembly_free(NULL);
}

static uint64_t hash_of(const char *text)
{
    lsqt_assembly a;
    lsqt_diag d;
    uint64_t h = 0;
    if (parse_good(text, &a, &d))
        h = lsqt_assembly_hash(&a);
    lsqt_assembly_free(&a);
    return h;
}

static void test_hash(void)
{
    uint64_t base = hash_of("Medium\nLayer z=0 Lambertian fR=0.6\nMedium\n");
    CHECK(base != 0, "hash 0");
    CHECK(base == hash_of("# c\nMedium eta=1\r\nLayer z=0 LambertianBsdf fT=0 fR=6e-1\n"
                          "Medium mua=0\n"), "same assembly, other text");
    CHECK(base != hash_of("Medium\nLayer z=0 Lambertian fR=0.61\nMedium\n"), "fR");
    CHECK(base != hash_of("Medium\nLayer z=1 Lambertian fR=0.6\nMedium\n"), "z");
    CHECK(base != hash_of("Medium eta=1.5\nLayer z=0 Lambertian fR=0.6\nMedium\n"), "eta");
    CHECK(base != hash_of("Medium\nLayer z=0 OrenNayarDiffuse fR=0.6 sigma=0\nMedium\n"), "model");
    CHECK(hash_of(LAYER2("MicrosurfaceLambertian alpha=0.3")) ==
          hash_of(LAYER2("MicrosurfaceLambertian alpha=0.3 iter_count=4")), "auto iter_count");
    CHECK(hash_of(LAYER2("MicrosurfaceLambertian")) !=
          hash_of(LAYER2("MicrosurfaceLambertian use_multiple_scattering=false")), "flag");
    /* FNV-1a 64 of the canonical text, checked against a direct computation */
    const char *text = "Medium eta=1 mua=0 mus=0\nLayer z=0 NullBsdf\nMedium eta=1 mua=0 mus=0\n";
    uint64_t h = 14695981039346656037ULL;
    for (const char *p = text; *p; p++)
        h = (h ^ (unsigned char)*p) * 1099511628211ULL;
    CHECK(hash_of(text) == h, "FNV-1a");
}

static void test_build_options(void)
{
    static const struct {
        const char *text, *want;
    } cases[] = {
        { "Medium\nLayer z=0 Null\nMedium\n", "" },
        { "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.2\n"
          "Layer z=0 LambertianBsdf fR=1 fT=0\nMedium\n",
          "-DLSQT_HAS_PHASE_HG=1 -DLSQT_HAS_BSDF_LAMBERTIAN=1" },
        { "Medium eta=1.1\nLayer z=3 Null\nMedium mus=1 HenyeyGreenstein2\n"
          "Layer z=2.5 MicrosurfaceDielectric\nMedium mus=5 Sggx\n"
          "Layer z=1 MicrosurfaceLambertian fR=0.2 fT=0.8\nMedium mus=2 Rayleigh\n"
          "Layer z=0 OrenNayarDiffuse\nMedium\n",
          "-DLSQT_HAS_PHASE_HG2=1 -DLSQT_HAS_PHASE_RAYLEIGH=1 -DLSQT_HAS_PHASE_SGGX=1 "
          "-DLSQT_HAS_BSDF_MS_LAMBERTIAN=1 -DLSQT_HAS_BSDF_MS_DIELECTRIC=1 "
          "-DLSQT_HAS_BSDF_OREN_NAYAR=1" },
        { "Medium\nLayer z=0 MicrosurfaceConductive\nMedium eta=0.2 mua=1\n",
          "-DLSQT_HAS_BSDF_MS_CONDUCTIVE=1" },
        /* pruned models are not built */
        { "Medium\nLayer z=1 OrenNayarDiffuse\nMedium mus=1 Rayleigh\nLayer z=0 Lambertian\nMedium\n",
          "-DLSQT_HAS_BSDF_OREN_NAYAR=1" },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        lsqt_assembly a;
        lsqt_diag d;
        if (!parse_good(cases[i].text, &a, &d))
            continue;
        char buf[512];
        size_t n = lsqt_assembly_build_options(&a, buf, sizeof buf);
        CHECK(strcmp(buf, cases[i].want) == 0 && n == strlen(cases[i].want), "[%s], want [%s]",
              buf, cases[i].want);
        char small[8];
        CHECK(lsqt_assembly_build_options(&a, small, sizeof small) == n &&
              strlen(small) == (n < 7 ? n : 7), "truncation");
        CHECK(lsqt_assembly_build_options(&a, NULL, 0) == n, "size query");
        lsqt_assembly_free(&a);
    }
}

/* TabulatedPhase table=@FILE: the table's errors (line and token), its normalisation and
 * order, and the canonical text, which names the table by its content. */
static char tab_dir[] = "/tmp/test_lsqt_tab.XXXXXX";

static const char *tab_file(const char *name, const char *content)
{
    static char path[256];
    snprintf(path, sizeof path, "%s/%s", tab_dir, name);
    FILE *f = fopen(path, "w");
    if (f) fputs(content, f), fclose(f);
    return path;
}

static int tab_parse(const char *path, lsqt_assembly *a, lsqt_diag *d)
{
    char text[512];
    snprintf(text, sizeof text, MEDIUM3("mus=1 TabulatedPhase table=@%s"), path);
    return parse(text, a, d);
}

static void tab_bad(const char *name, const char *content, const char *msg)
{
    lsqt_assembly a;
    lsqt_diag d;
    const char *path = content ? tab_file(name, content) : name;
    CHECK(tab_parse(path, &a, &d) == 2 && d.error_line == 3, "%s: rc/line %d", name, d.error_line);
    CHECK(strstr(d.error, "unreadable phase table at 'table=@") && strstr(d.error, msg), "%s: [%s] lacks [%s]", name,
          d.error, msg);
}

static void test_phase_table(void)
{
    if (!mkdtemp(tab_dir)) {
        CHECK(0, "mkdtemp");
        return;
    }
    tab_bad("/nonexistent/t.txt", NULL, "cannot open");
    tab_bad("one.txt", "1\n-1\n", "one.txt:1: one column at '1'");
    tab_bad("three.txt", "1 1 1\n-1 1 1\n", "three.txt:1: more than two columns");
    tab_bad("word.txt", "# mu p\n1 abc\n-1 1\n", "word.txt:2: 'abc' is not a number");
    tab_bad("range.txt", "1 1\n0 1\n-1.5 1\n", "range.txt:3: cos theta '-1.5' outside [-1, 1]");
    tab_bad("neg.txt", "-1 1\n0 -0.5\n1 1\n", "neg.txt:2: value '-0.5' is negative");
    tab_bad("few.txt", "1 1\n", "too few rows (1)");
    tab_bad("cover.txt", "-1 1\n0.5 1\n", "covers [-1, 0.5]");
    tab_bad("order.txt", "-1 1\n0.5 1\n0 1\n1 1\n", "order.txt:3: cos theta '0' after 0.5");
    tab_bad("zero.txt", "-1 0\n1 0\n", "integrates to 0");
    lsqt_assembly a, b;
    lsqt_diag d;
    CHECK(parse(MEDIUM3("mus=1 TabulatedPhase"), &a, &d) == 2 && strstr(d.error, "missing required key table"), "%s",
          d.error);
    CHECK(parse(MEDIUM3("mus=1 TabulatedPhase table=@x,@y"), &a, &d) == 2 &&
              strstr(d.error, "a phase table is the same in every band"), "%s", d.error);
    CHECK(parse(MEDIUM3("mus=1 HenyeyGreensteinPhase g=@x"), &a, &d) == 2 &&
              strstr(d.error, "cos theta is a key of a tabulated model"), "%s", d.error);
    /* normalised (2 pi int p dmu = 1, exact for the linear interpolation), turned round,
     * the same whatever the scale; canonical text by content, not by name */
    const char *up = "-1 1\n0 3\n1 5\n", *down = "1 10 # cos theta descending, x2\n0 6\n-1 2\n";
    if (tab_parse(tab_file("up.txt", up), &a, &d) == 0) {
        if (tab_parse(tab_file("down.txt", down), &b, &d) == 0) {
            const lsqt_phase_table *t = &a.phase_tables[0], *u = &b.phase_tables[0];
            const double norm = 1 / (2 * 3.14159265358979323846 * 6); /* int = (1 + 3) / 2 + (3 + 5) / 2 */
            CHECK(a.n_phase_tables == 1 && a.media[1].phase.table == 1 && t->n == 3, "one table of 3 rows");
            CHECK(t->mu[0] == -1 && t->mu[2] == 1 && fabs(t->p[1] - 3 * norm) < 1e-15 && fabs(t->cdf[1] - 4.0 / 12) < 1e-15 &&
                      t->cdf[2] == 1, "normalised: p %.17g cdf %.17g", t->p[1], t->cdf[1]);
            CHECK(u->mu[0] == -1 && fabs(u->p[0] - t->p[0]) < 1e-15 && fabs(u->p[2] - t->p[2]) < 1e-15, "descending, x2");
            char *ca = canonical(&a), *cb = canonical(&b);
            CHECK(ca && cb && strcmp(ca, cb) == 0 && strstr(ca, "TabulatedPhase table=@3rows:"),
                  "a table and its multiple, by other names: [%s] [%s]", ca, cb);
            free(cb);
            lsqt_assembly_free(&b);
            if (tab_parse(tab_file("other.txt", "-1 1\n0 3\n1 5.001\n"), &b, &d) == 0) { /* another table */
                cb = canonical(&b);
                CHECK(ca && cb && strcmp(ca, cb) != 0 && lsqt_assembly_hash(&a) != lsqt_assembly_hash(&b),
                      "another table, the same text: [%s] [%s]", ca, cb);
                free(cb);
                lsqt_assembly_free(&b);
            }
            free(ca);
        } else
            CHECK(0, "%s", d.error);
        lsqt_assembly_free(&a);
    } else
        CHECK(0, "%s", d.error);
    const char *names[] = {"one.txt", "three.txt", "word.txt", "range.txt", "neg.txt", "few.txt", "cover.txt",
                           "order.txt", "zero.txt", "up.txt", "down.txt", "other.txt"};
    char path[256];
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        snprintf(path, sizeof path, "%s/%s", tab_dir, names[i]), remove(path);
    remove(tab_dir);
}

int main(void)
{
    test_phase_table();
    test_bad_inputs();
    test_garbage();
    test_tutorials();
    test_bsdf_defaults();
    test_phase_defaults();
    test_every_key();
    test_aliases();
    test_layout();
    test_numbers();
    test_iter_count_auto();
    test_notes();
    test_pruning();
    test_round_trip();
    test_canonical_text();
    test_hash();
    test_build_options();
    return check_finish("test_lsqt");
}
