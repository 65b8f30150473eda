#!/usr/bin/env bash
# lssview: the Lambertian sphere (EXR, linear, one light or the default three) follows the
# cosine law at 20 sample pixels and at every pixel (no spikes or holes) within 1 %, the
# rim beyond the last slice (θo_max, from `lsqt-cl info --json`) included: it is held
# from the last slice, so the default picture (PNG) has no magenta pixel, and the summary
# line names the held rim and its pixel count; --strict makes exactly the rim pixels
# (θo > θo_max, counted here from the geometry) magenta, the rest still on the cosine law;
# on a non-Lambertian stack (a rough dielectric) every rim pixel equals the last slice's
# estimates interpolated as lssview.cpp documents (recomputed here from `info --bsdf`),
# its --error colour too, and differs from what the first slice would give; fR = 0 gives
# a black sphere; a sharp rough dielectric coat (alpha 0.05) has its highlight where the
# half vector of light and camera is the normal, within 2 pixels; --error on 4x the paths
# (the same LSS continued) shows about half the relative error (within 15 %); runs with
# bands: R, G, B bands are the channels (each on its own cosine law), --channel K is band K
# in grey (the pixels of a one-band run of the same values), a flat spectrum is grey and a
# red one red all over; the defaults (IN.lss.png, 512x512 PNG), --image-dim and
# --image-mul; and truncated, damaged, other-version and missing LSS files, bad flags, a
# band that is not there: exit 2 with a message.
# usage: test_lssview.sh LSQT_CL LSSVIEW IMAGE_DUMP EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN VIEW DUMP EX -- "$@"
cli_workdir

# check.py MODE IMAGE ARGS...: reads IMAGE through image_dump; the sphere geometry of
# lssview.cpp (radius 0.45 of the width, orthographic, view +z). THMAX: θo of the last
# slice, radians; a pixel is on the rim when its centre's θo is beyond it.
cat > check.py <<'PY'
import json, math, random, struct, subprocess, sys
mode, img = sys.argv[1], sys.argv[2]
CH = 0  # the channel the cosine law is checked on: MODE@K checks channel K
if "@" in mode: mode, CH = mode.split("@")[0], int(mode.split("@")[1])
a = sys.argv[3:-1]  # the last one is image_dump
if mode == "ratio":  # ratio A B WANT TOL: A / B within TOL (relative) of WANT
    ra = float(a[0]) / float(a[1])
    print("relative error ratio %.4g (want %s within %s)" % (ra, a[2], a[3]))
    sys.exit(0 if abs(ra - float(a[2])) <= float(a[3]) * float(a[2]) else 1)
data = subprocess.run([sys.argv[-1], img], capture_output=True, check=True).stdout
nl = data.index(b"\n")
W, H, C = map(int, data[:nl].split())
px = struct.unpack("<%df" % (W * H * C), data[nl + 1:])
rad = 0.45 * W
def pix(i, j): return px[(j * W + i) * C:(j * W + i) * C + 3]
def magenta(p): return p[0] == 1 and p[1] == 0 and p[2] == 1
def normal(i, j):
    x, y = (i + 0.5 - W / 2) / rad, (W / 2 - j - 0.5) / rad
    r2 = x * x + y * y
    return None if r2 >= 1 else (x, y, math.sqrt(1 - r2))
TH = {}
def theta_o(i, j):
    if (i, j) not in TH: TH[i, j] = math.acos(min(1.0, normal(i, j)[2]))
    return TH[i, j]
def lights(v):  # LX LY LZ E ... -> [((x, y, z) unit, E)]
    out = []
    for k in range(0, len(v), 4):
        d = list(map(float, v[k:k + 3])); n = math.sqrt(sum(c * c for c in d))
        out.append((tuple(c / n for c in d), float(v[k + 3])))
    return out
def dot(p, q): return sum(x * y for x, y in zip(p, q))
sphere = [] if mode in ("size", "ratio") else [(i, j) for j in range(H) for i in range(W) if normal(i, j)]
covered = [(i, j) for (i, j) in sphere if not magenta(pix(i, j))]
bad = []
if mode in ("cosine", "strict"):  # cosine THMAX FR L..., strict THMAX NMAG FR L...; L: LX LY LZ E
    if mode == "strict":  # the summary line's count of magenta pixels
        nmag = a.pop(1)
        nmag = int(nmag) if nmag.isdigit() else -1
    thmax, fr = float(a[0]), float(a[1])
    Ls = lights(a[2:])
    rim = set(p for p in sphere if theta_o(*p) > thmax)
    # the pixels whose centre is within 1e-9 rad of θo_max may go either way (rounding)
    edge = set(p for p in sphere if abs(TH[p] - thmax) <= 1e-9)
    mag = set(sphere) - set(covered)
    if not rim: bad.append("no rim pixel beyond θo %.4g: nothing tested" % thmax)
    if mode == "cosine" and mag:
        bad.append("%d magenta sphere pixels (%d of them on the rim), e.g. %s" % (len(mag), len(mag & rim), min(mag)))
    if mode == "strict":
        if (mag ^ rim) - edge:
            bad.append("--strict: %d magenta pixels, %d rim pixels (θo > %.6g), %d differ beyond rounding" %
                       (len(mag), len(rim), thmax, len((mag ^ rim) - edge)))
        print("strict: %d magenta pixels, %d rim pixels from the geometry, %d at the edge" %
              (len(mag), len(rim), len(edge)))
        if nmag != len(mag): bad.append("the summary says %d magenta (-1: no count), the image has %d" % (nmag, len(mag)))
    Esum = sum(E for _, E in Ls)
    def want(i, j): return fr / math.pi * sum(max(0.0, dot(normal(i, j), L)) * E for L, E in Ls)
    rnd = random.Random(11)
    samples = rnd.sample(covered, 20)
    worst = worst_rim = 0.0
    for (i, j) in samples:
        v, w = pix(i, j)[CH], want(i, j)
        if abs(v - w) > 0.01 * max(w, 1e-3 * fr / math.pi * Esum):
            bad.append("sample pixel (%d, %d): %.6g, cosine law %.6g" % (i, j, v, w))
    for (i, j) in covered:  # every pixel: no spike, no hole
        v, w = pix(i, j)[CH], want(i, j)
        d = abs(v - w) / max(w, 1e-3 * fr / math.pi * Esum)
        worst = max(worst, d)
        if (i, j) in rim: worst_rim = max(worst_rim, d)
    if worst > 0.01: bad.append("a covered pixel is %.3g off the cosine law (relative)" % worst)
    nrim = len(rim & set(covered))
    print("cosine law: 20 samples and %d covered pixels, worst relative deviation %.3g; %d rim pixels beyond "
          "θo %.2f°, worst %.3g" % (len(covered), worst, nrim, math.degrees(thmax), worst_rim))
elif mode == "nomagenta":  # nomagenta THMAX NHELD: no magenta sphere pixel; NHELD: the summary's count
    thmax, nheld = float(a[0]), int(a[1]) if a[1:] and a[1].isdigit() else -1
    mag = [p for p in sphere if magenta(pix(*p))]
    rim = [p for p in sphere if theta_o(*p) > thmax]
    print("%d magenta of %d sphere pixels, %d rim pixels beyond θo %.2f°" % (len(mag), len(sphere), len(rim),
                                                                          math.degrees(thmax)))
    if mag: bad.append("%d magenta sphere pixels, e.g. %s (θo %.2f°)" % (len(mag), mag[0], math.degrees(theta_o(*mag[0]))))
    if not rim: bad.append("no rim pixel: nothing tested")
    if nheld != len(rim):
        bad.append("the summary says %d held rim pixels (-1: no count), the geometry %d" % (nheld, len(rim)))
elif mode == "held":  # held INFO.json LX LY LZ E [ERROR_IMAGE EMAX]: the rim's values are the last slice's
    info = json.load(open(a[0]))
    (L, E), = lights(a[1:5])
    up = sorted((s for s in info["slices"] if not s["from_below"]), key=lambda s: s["theta_o"])
    def pts(sl):  # lssview's scattered data: upper hemisphere, mirror images in y
        out = []
        for x, y, z, f, e in sl["bsdf"]:
            if not z > 0 or f is None: continue
            n = math.sqrt(x * x + y * y + z * z); d = (x / n, y / n, z / n)
            out.append((d, f, e))
            if d[1] > 1e-7: out.append(((d[0], -d[1], d[2]), f, e))
        return out
    R0 = 2 * math.sin(math.radians(40) / 2)  # the default --max-gap, as a chord
    def interp(P, q):  # K = 8 nearest, weight (1 - (d/R)²)², R = min(9th nearest, R0)
        near = sorted((sum((u - v) ** 2 for u, v in zip(d, q)), f, e) for d, f, e in P)[:9]
        R2 = min(R0 * R0, near[8][0]) if len(near) == 9 else R0 * R0
        sw = sf = se = 0.0
        for d2, f, e in near[:8]:
            if d2 >= R2: break
            w = (1 - d2 / R2) ** 2; sw += w; sf += w * f; se += w * e
        return (sf / sw, se / sw) if sw > 0 else None
    last, first = pts(up[-1]), pts(up[0])
    thmax = up[-1]["theta_o"]
    def frame(i, j):  # wi of L in the pixel's frame: z = n, x = V on the tangent plane
        n = normal(i, j); t = [-n[2] * c for c in n]; t[2] += 1
        tl = math.sqrt(dot(t, t)); t = [c / tl for c in t]
        b = (n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0])
        return (dot(L, t), dot(L, b), dot(L, n))
    rim = [p for p in sphere if theta_o(*p) > thmax and frame(*p)[2] > 0]
    got, want, other, gap, hole = [], [], [], [], []
    for p in rim:
        wi = frame(*p)
        fe = interp(last, wi)
        if fe is None:  # a real gap in the data: magenta in both modes
            if not magenta(pix(*p)): gap.append(p)
            continue
        if magenta(pix(*p)): hole.append(p); continue
        got.append(pix(*p)[0]); want.append(E * wi[2] * fe[0])
        f0 = interp(first, wi); other.append(E * wi[2] * f0[0] if f0 else float("nan"))
    top = max(want) if want else 0.0
    dev = max((abs(g - w) / max(w, 1e-4 * top) for g, w in zip(got, want)), default=0.0)
    far = [abs(o - w) / max(w, 1e-4 * top) for o, w in zip(other, want) if o == o]
    print("held rim: %d lit rim pixels beyond θo %.2f°, value %.4g..%.4g, worst relative deviation from the last "
          "slice %.3g, from the first slice up to %.3g" % (len(got), math.degrees(thmax), min(want, default=0),
                                                          top, dev, max(far, default=0)))
    if gap: bad.append("%d rim pixels with no estimate within 40° are not magenta, e.g. %s" % (len(gap), gap[0]))
    if hole: bad.append("%d rim pixels with an estimate are magenta, e.g. %s" % (len(hole), hole[0]))
    if len(got) < 100: bad.append("only %d lit rim pixels with a value: nothing much tested" % len(got))
    if dev > 1e-4: bad.append("a rim pixel is %.3g off the last slice's value (relative)" % dev)
    if max(far, default=0) < 0.5: bad.append("the first slice gives about the same rim: the test tells nothing")
    if len(a) > 5:  # the --error image (linear, --error-max EMAX): the false colour of err / value
        stops = [(0.05, 0.05, 0.35), (0.1, 0.35, 0.9), (0.1, 0.75, 0.3), (0.95, 0.9, 0.1), (0.9, 0.1, 0.05)]
        def fc(u):
            u = min(1.0, max(0.0, u)) * 4; k = min(3, int(u))
            return [s + (t - s) * (u - k) for s, t in zip(stops[k], stops[k + 1])]
        emax = float(a[6])
        ed = subprocess.run([sys.argv[-1], a[5]], capture_output=True, check=True).stdout
        EW = int(ed[:ed.index(b"\n")].split()[0])
        epx = struct.unpack("<%df" % ((len(ed) - ed.index(b"\n") - 1) // 4), ed[ed.index(b"\n") + 1:])
        worst_c = 0.0; n_c = 0
        for p in rim:
            wi = frame(*p); fe = interp(last, wi)
            if fe is None or not fe[0] > 0: continue
            c = fc(fe[1] / fe[0] / emax); k = (p[1] * EW + p[0]) * 3
            worst_c = max(worst_c, max(abs(x - y) for x, y in zip(c, epx[k:k + 3]))); n_c += 1
        print("--error rim: %d pixels, worst colour deviation %.3g" % (n_c, worst_c))
        if worst_c > 1e-4 or n_c < 100: bad.append("--error: the rim is not the last slice's error")
elif mode == "black":
    if len(covered) < 0.5 * len(sphere): bad.append("only %d of %d covered" % (len(covered), len(sphere)))
    m = max(max(pix(i, j)) for (i, j) in covered)
    if m != 0: bad.append("fR = 0 sphere has a pixel of %g" % m)
    print("black: %d covered pixels, max %g" % (len(covered), m))
elif mode == "highlight":  # highlight LX LY LZ
    lx, ly, lz = map(float, a[:3])
    n = math.sqrt(lx * lx + ly * ly + lz * lz); L = (lx / n, ly / n, lz / n + 1)
    n = math.sqrt(sum(c * c for c in L)); h = [c / n for c in L]
    ei, ej = W / 2 + h[0] * rad - 0.5, W / 2 - h[1] * rad - 0.5
    v, i, j = max((pix(i, j)[0], i, j) for (i, j) in covered)
    d = math.hypot(i - ei, j - ej)
    print("highlight %.4g at (%d, %d), mirror direction at (%.1f, %.1f): %.2f px" % (v, i, j, ei, ej, d))
    if d > 2: bad.append("highlight %.2f px from the mirror direction" % d)
elif mode == "scaled":  # scaled OTHER_IMAGE FACTOR: this image = FACTOR x OTHER
    o = subprocess.run([sys.argv[-1], a[0]], capture_output=True, check=True).stdout
    po = struct.unpack("<%df" % (W * H * C), o[o.index(b"\n") + 1:])
    f = float(a[1])
    for (i, j) in covered:
        k = (j * W + i) * C
        if abs(px[k] - f * po[k]) > 1e-5 * max(1.0, abs(px[k])): bad.append("pixel (%d, %d)" % (i, j)); break
elif mode == "same":  # same OTHER_IMAGE: the same pixels
    o = subprocess.run([sys.argv[-1], a[0]], capture_output=True, check=True).stdout
    if o != subprocess.run([sys.argv[-1], img], capture_output=True, check=True).stdout: bad.append("differs from %s" % a[0])
elif mode == "grey":  # every sphere pixel has R = G = B (to float rounding)
    g = [p for p in covered if max(pix(*p)) - min(pix(*p)) > 1e-6 * max(pix(*p))]
    if g: bad.append("%d of %d pixels not grey, e.g. %s: %s" % (len(g), len(covered), g[0], pix(*g[0])))
    print("grey: %d pixels" % len(covered))
elif mode == "red":  # red MIN: the lit pixels (R > MIN) have R > G > B; CHROMA: and one chromaticity
    lit = [pix(*p) for p in covered if pix(*p)[0] > float(a[0])]
    wrong = [q for q in lit if not q[0] > q[1] > q[2]]
    if len(lit) < 0.3 * len(sphere): bad.append("only %d lit pixels" % len(lit))
    if wrong: bad.append("%d of %d lit pixels not R > G > B, e.g. %s" % (len(wrong), len(lit), wrong[0]))
    r = [q[0] / sum(q) for q in lit]
    print("red: %d lit pixels, R > G > B in %d; r = R / (R + G + B) %.6g to %.6g" % (len(lit), len(lit) - len(wrong),
                                                                                     min(r), max(r)))
    if a[1:] and a[1] == "chroma" and max(r) - min(r) > 1e-5: bad.append("the colour varies over the sphere")
elif mode == "size":  # size W H C
    if (W, H, C) != tuple(map(int, a[:3])): bad.append("size %dx%dx%d" % (W, H, C))
for b in bad: print("FAIL:", b)
sys.exit(1 if bad else 0)
PY
check() { if python3 check.py "$@" "$DUMP"; then ok; else bad "check.py $*"; fi; }

printf 'Medium\nLayer z=0 LambertianBsdf fR=0 fT=0\nMedium\n' > black.lsqt
printf 'Medium\nLayer z=1 MicrosurfaceDielectricBsdf alpha=0.05\nMedium eta=1.5\nLayer z=0 LambertianBsdf fR=0 fT=0\nMedium\n' > coat.lsqt
cp "$EX/tutorial/Lambertian.lsqt" L.lsqt
"$BIN" -q -p 20000 -wo 8 -wi 80 --lss L.lss -o L.raw L.lsqt || bad "lsqt-cl L.lsqt"
"$BIN" -q -p 5000 -wo 8 -wi 80 --lss B.lss -o B.raw black.lsqt || bad "lsqt-cl black.lsqt"
"$BIN" -q -p 20000 -wo 12 -wi 80 --lss C.lss -o C.raw coat.lsqt || bad "lsqt-cl coat.lsqt"

# θo of the last slice from above (radians, as the LSS holds it) and in degrees as the
# summary line prints it; -wo 8 puts it at 0.99·90°·7/8
thmax() { python3 -c 'import json, sys
s = [x["theta_o"] for x in json.load(open(sys.argv[1]))["slices"] if not x["from_below"]]
print(repr(max(s)))' "$1"; }
deg() { python3 -c 'import math, sys; print("%.1f" % math.degrees(float(sys.argv[1])))' "$1"; }
"$BIN" info L.lss --json L.json > /dev/null || bad "lsqt-cl info L.lss"
TL=$(thmax L.json)
python3 -c 'import math, sys; sys.exit(abs(float(sys.argv[1]) - 0.99 * math.pi / 2 * 7 / 8) > 1e-12)' "$TL" && ok ||
  bad "the last of 8 slices is at θo $TL rad, not 0.99·90°·7/8"
# has TEXT: the last command's output ($out) holds TEXT
has() { if grep -qF -- "$1" <<<"$out"; then ok; else bad "output lacks '$1': $out"; fi; }

# the cosine law (fR = 0.6), one light of irradiance 2, the rim beyond θo_max included
expect 0 "wrote L.exr (512x512), 0 of" -- "$VIEW" L.lss -o L.exr --light -0.4,0.5,1,2
check cosine L.exr "$TL" 0.6 -0.4 0.5 1 2
expect 0 "" -- "$VIEW" L.lss -o L2.exr --light=0.9,-0.2,0.4,1
check cosine L2.exr "$TL" 0.6 0.9 -0.2 0.4 1
# ... and under the default lights
expect 0 "" -- "$VIEW" -q --image-dim 256 L.lss -o L4.exr
check cosine L4.exr "$TL" 0.6 -1 1 1.2 2.5 1 0.2 0.6 0.8 0 1 -0.3 1.2
# defaults: IN.lss.png, 512x512 RGB, a whole sphere (no magenta), and the summary line
# names the held rim and its pixel count (checked against the geometry)
out=$("$VIEW" L.lss 2>&1) && ok || bad "lssview L.lss: $out"
has "wrote L.lss.png (512x512), 0 of"
has "; rim beyond θo $(deg "$TL")° held from the last slice ("
has "--strict shows it magenta"
check size L.lss.png 512 512 3
check nomagenta L.lss.png "$TL" "$(sed -n 's/.*held from the last slice (\([0-9]*\) pixels, .*/\1/p' <<<"$out")"
# --strict: magenta exactly on the rim, the rest as before; the summary counts it
out=$("$VIEW" --strict --image-dim 256 L.lss -o Ls.exr --light -0.4,0.5,1,2 2>&1) && ok || bad "lssview --strict: $out"
has ", the rim beyond θo $(deg "$TL")° included (--strict)"
check strict Ls.exr "$TL" "$(sed -n 's/.*), \([0-9]*\) of [0-9]* sphere pixels not covered.*/\1/p' <<<"$out")" \
  0.6 -0.4 0.5 1 2
# -q: no summary line
out=$("$VIEW" -q --image-dim 100 -o small.png L.lss 2>&1) && [ -z "$out" ] && ok || bad "lssview -q printed '$out'"
check size small.png 100 100 3
expect 0 "" -- "$VIEW" -q --image-mul 2.5 -o L3.exr --light -0.4,0.5,1,2 L.lss
check scaled L3.exr L.exr 2.5

# an all-black BSDF gives a black sphere
expect 0 "" -- "$VIEW" -q B.lss -o B.exr
check black B.exr

# the highlight of a sharp rough dielectric (over black) where the half vector is the normal
for L in -0.5,0.3,1 0.7,-0.2,1; do
  expect 0 "" -- "$VIEW" -q C.lss -o "C$L.exr" --light "$L,1"
  check highlight "C$L.exr" ${L//,/ }
done

# a rough dielectric (not constant in θo): the rim holds the last slice's values and
# errors; the light from behind puts the last slice's grazing reflection on the rim
"$BIN" info C.lss --json C.json --bsdf > /dev/null || bad "lsqt-cl info --bsdf C.lss"
expect 0 "" -- "$VIEW" -q --image-dim 256 C.lss -o Crim.exr --light 0.3,1,-0.5,1
expect 0 "" -- "$VIEW" -q --image-dim 256 --error --error-max 0.2 C.lss -o Crim.err.exr --light 0.3,1,-0.5,1
check held Crim.exr C.json 0.3 1 -0.5 1 Crim.err.exr 0.2

# Bands. A red Lambertian in R, G, B (fR 0.7, 0.3, 0.1): each channel on the cosine law of
# its own fR (the bands are the channels, as they are); the PNG's lit pixels R > G > B;
# --channel 1 is grey and has exactly the pixels of a one-band run of fR 0.3 on the same
# directions (--wi-spread). A flat spectrum (0.5 at 450, 550, 650 nm) is grey on the
# cosine law of 0.5; a red one (0.1, 0.2, 0.8) has R > G > B and one chromaticity over the
# sphere. --error shows the bands' luminance error, or one band's with --channel. Small
# images: the sanitizer suite runs all of this too.
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.7,0.3,0.1\nMedium\n' > red.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3\nMedium\n' > g.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.1,0.2,0.8\nMedium\n' > spec.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > flat.lsqt
# (each band on paths of its own, LSQT_BAND_BLOCK=1, so that band 1 is the one-band run
# bit for bit)
LSQT_BAND_BLOCK=1 "$BIN" -q -p 2000 -wo 8 -wi 80 --wi-spread --lss red.lss -o red.raw red.lsqt || bad "lsqt-cl red.lsqt"
"$BIN" -q -p 2000 -wo 8 -wi 80 --wi-spread --lss g.lss -o g.raw g.lsqt || bad "lsqt-cl g.lsqt"
"$BIN" -q -p 2000 -wo 8 --wavelengths 450,550,650 --lss flat.lss -o flat.raw flat.lsqt || bad "lsqt-cl flat.lsqt"
"$BIN" -q -p 2000 -wo 8 --wavelengths 450,550,650 --lss spec.lss -o spec.raw spec.lsqt || bad "lsqt-cl spec.lsqt"
"$BIN" info red.lss --json red.json > /dev/null || bad "lsqt-cl info red.lss"
TR=$(thmax red.json)
expect 0 "; colour from bands R, G, B" -- "$VIEW" --image-dim 160 red.lss -o red.exr --light -0.4,0.5,1,2
check cosine@0 red.exr "$TR" 0.7 -0.4 0.5 1 2
check cosine@1 red.exr "$TR" 0.3 -0.4 0.5 1 2
check cosine@2 red.exr "$TR" 0.1 -0.4 0.5 1 2
expect 0 "" -- "$VIEW" -q --image-dim 128 red.lss -o red.png
check red red.png 0.2
expect 0 "; band 1 (G) of 3 in grey (--channel)" -- "$VIEW" --image-dim 160 --channel 1 red.lss -o red1.exr
expect 0 "" -- "$VIEW" -q --image-dim 160 g.lss -o g.exr
check grey red1.exr
check same red1.exr g.exr
expect 0 "; colour from a spectrum at 3 wavelengths, 450 to 650 nm (linear sRGB)" -- \
  "$VIEW" --image-dim 160 flat.lss -o flat.exr --light -0.4,0.5,1,2
check grey flat.exr
check cosine flat.exr "$(thmax <("$BIN" info flat.lss --json - 2>/dev/null))" 0.5 -0.4 0.5 1 2
expect 0 "" -- "$VIEW" -q --image-dim 160 spec.lss -o spec.exr
check red spec.exr 0.01 chroma
sed 's/mus=1 /mus=1,2,0.5 /' "$EX/slab.lsqt" > P.lsqt  # the slab in R, G, B: errors that are not 0
"$BIN" -q -p 3000 -wo 4 -wi 48 --lss P.lss -o P.raw P.lsqt || bad "lsqt-cl P.lsqt"
out=$("$VIEW" --error --image-dim 128 P.lss -o Perr.png 2>&1) && ok || bad "lssview --error on bands: $out"
has "; bands R, G, B: the error of their luminance"
has "relative error: median "
out=$("$VIEW" --error --channel 2 --image-dim 128 P.lss -o Perr2.png 2>&1) && ok || bad "lssview --error --channel: $out"
has "band 2 (B) of 3 in grey (--channel)"
check size Perr2.png 168 128 3
# refused: a band that is not there, a bad K, unnamed bands other than three without --channel
expect 2 "--channel 3: 'red.lss' has 3 bands: K must be 0 to 2" -- "$VIEW" --channel 3 red.lss -o x.png
expect 2 "--channel 1: 'L.lss' has one band: K must be 0" -- "$VIEW" --channel 1 L.lss -o x.png
expect 2 "--channel: '1.5' is not a whole number" -- "$VIEW" --channel 1.5 red.lss -o x.png
expect 2 "--channel: '-1' is not a number in [0," -- "$VIEW" --channel -1 red.lss -o x.png
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5,0.2\nMedium\n' > two.lsqt
"$BIN" -q -p 300 -wo 4 --lss two.lss -o two.raw two.lsqt || bad "lsqt-cl two.lsqt"
expect 2 "'two.lss' has 2 bands without wavelengths, which make no colour: choose one with --channel K (0 to 1)" -- \
  "$VIEW" two.lss -o x.png
[ ! -e x.png ] && ok || bad "a refused preview wrote x.png"
expect 0 "band 1 (1) of 2 in grey" -- "$VIEW" --image-dim 64 --channel 1 two.lss -o two1.png
expect 0 "--channel K" -- "$VIEW" --help

# --error: 4x the paths (the same directions: the LSS continued) halve the relative error
"$BIN" -q -p 20000 -wo 6 -wi 48 --lss E.lss -o E.raw "$EX/slab.lsqt" || bad "lsqt-cl slab"
cp E.lss E1.lss
"$BIN" -q -p 60000 --lss E.lss -o E.raw "$EX/slab.lsqt" || bad "lsqt-cl slab continued"
m1=$("$VIEW" --error E1.lss | sed -n 's/^relative error: median \([^,]*\),.*/\1/p')
m4=$("$VIEW" --error E.lss | sed -n 's/^relative error: median \([^,]*\),.*/\1/p')
[ -s E1.lss.error.png ] && [ -s E.lss.error.png ] && ok || bad "--error wrote no image"
check size E.lss.error.png 597 512 3
if [ -n "$m1" ] && [ -n "$m4" ]; then check ratio - "$m4" "$m1" 0.5 0.15; else bad "no median error printed"; fi
"$BIN" -q -p 200 -wo 4 -wi 16 --lss few.lss -o few.raw L.lsqt || bad "lsqt-cl -p 200"
expect 2 "too few paths" -- "$VIEW" --error few.lss -o x.png

# files it refuses: exit 2, a message, no image
size=$(stat -c %s L.lss)
head -c $((size / 2)) L.lss > trunc.lss
expect 2 "truncated" -- "$VIEW" trunc.lss -o t.png
expect 2 "truncated" -- "$VIEW" --error trunc.lss -o t.png
[ ! -e t.png ] && ok || bad "an image of a truncated LSS"
cp L.lss damaged.lss
printf '\x5a' | dd of=damaged.lss bs=1 seek=$((size / 3)) conv=notrunc status=none
expect 2 "CRC" -- "$VIEW" damaged.lss -o t.png
cp L.lss v9.lss
printf '\x09' | dd of=v9.lss bs=1 seek=8 conv=notrunc status=none
expect 2 "version 9" -- "$VIEW" v9.lss -o t.png
: > empty.lss
expect 2 "empty" -- "$VIEW" empty.lss -o t.png
# One input rule with lsqt-cl: only a regular file is read (a FIFO hung, a device was
# "empty"). The null device is made here, never the system's.
mkfifo in.fifo
expect 2 "'in.fifo' is a FIFO, not an LSS file (only regular files are read)" -- "$VIEW" in.fifo -o t.png
if mknod nulldev c 1 3 2>/dev/null; then
  expect 2 "'nulldev' is a character device, not an LSS file" -- "$VIEW" nulldev -o t.png
fi
expect 2 "" -- "$VIEW" missing.lss
expect 2 "unknown option" -- "$VIEW" --nope L.lss
expect 2 "--image-dim" -- "$VIEW" --image-dim 0 L.lss
expect 2 "--light" -- "$VIEW" --light 1,2 L.lss
expect 2 "" -- "$VIEW"
expect 0 "--image-dim" -- "$VIEW" --help
expect 0 "--strict" -- "$VIEW" --help
[ ! -e t.png ] && ok || bad "an image of a refused LSS"

# Where the image goes (util.h's rules, as lsqt-cl's outputs): never over the input, a
# folder or an extension without a writer refused before any work, and written through
# a temporary that must read back whole before it replaces anything.
cp L.lss in.png
expect 2 "the output 'in.png' would replace the input" -- "$VIEW" -q in.png -o in.png
cmp -s L.lss in.png && ok || bad "lssview wrote over its input"
mkdir -p adir
expect 1 "cannot write 'adir': it is a directory" -- "$VIEW" L.lss -o adir
expect 2 "OpenImageIO has no writer for its extension" -- "$VIEW" L.lss -o x.nosuchformat
# A full file system (a small tmpfs, as root): exit 1 naming the image, the old one kept,
# no new or half-written file, no temporaries.
if cli_tmpfs small 2m; then
  expect 0 "wrote small/old.exr" -- "$VIEW" L.lss -o small/old.exr
  cp small/old.exr keep.exr
  dd if=/dev/zero of=small/filler bs=4k 2>/dev/null
  expect 1 "cannot write 'small/old.exr'" -- "$VIEW" L.lss -o small/old.exr
  cmp -s small/old.exr keep.exr && ok || bad "a full disk damaged the old image"
  expect 1 "cannot write 'small/new.png'" -- "$VIEW" L.lss -o small/new.png
  [ ! -e small/new.png ] && ok || bad "a half-written small/new.png exists"
  ! ls small | grep -q tmp && ok || bad "temporaries left: $(ls small)"
  umount small
else
  echo "skip: cannot mount a tmpfs here (not root?): full-disk checks skipped"
fi
finish test_lssview
