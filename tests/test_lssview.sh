#!/usr/bin/env bash
# lssview: the Lambertian sphere (EXR, linear, one light) follows the cosine law at 20
# sample pixels and at every covered pixel (no spikes or holes) within 1 %; fR = 0 gives a
# black sphere; a sharp rough dielectric coat (alpha 0.05) has its highlight where the
# half vector of light and camera is the normal, within 2 pixels; --error on 4x the paths
# (the same LSS continued) shows about half the relative error (within 15 %); the
# defaults (IN.lss.png, 512x512 PNG), --image-dim and --image-mul; and truncated, damaged,
# other-version and missing LSS files, bad flags: exit 2 with a message.
# usage: test_lssview.sh LSQT_CL LSSVIEW IMAGE_DUMP EXAMPLES_DIR
set -u
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
BIN=$1
VIEW=$2
DUMP=$3
EX=$4
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cd "$T"

# check.py MODE IMAGE ARGS...: reads IMAGE through image_dump; the sphere geometry of
# lssview.cpp (radius 0.45 of the width, orthographic, view +z).
cat > check.py <<'PY'
import math, random, struct, subprocess, sys
mode, img = sys.argv[1], sys.argv[2]
a = sys.argv[3:]
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
sphere = [(i, j) for j in range(H) for i in range(W) if normal(i, j)]
covered = [(i, j) for (i, j) in sphere if not magenta(pix(i, j))]
bad = []
if mode == "cosine" and len(covered) < 0.9 * len(sphere):
    bad.append("only %d of %d sphere pixels covered" % (len(covered), len(sphere)))
if mode == "cosine":  # cosine FR LX LY LZ E
    fr, lx, ly, lz, E = map(float, a[:5])
    n = math.sqrt(lx * lx + ly * ly + lz * lz); L = (lx / n, ly / n, lz / n)
    def want(i, j): return fr / math.pi * max(0.0, sum(p * q for p, q in zip(normal(i, j), L))) * E
    rnd = random.Random(11)
    samples = rnd.sample(covered, 20)
    worst = 0.0
    for (i, j) in samples:
        v, w = pix(i, j)[0], want(i, j)
        if abs(v - w) > 0.01 * max(w, 1e-3 * fr / math.pi * E):
            bad.append("sample pixel (%d, %d): %.6g, cosine law %.6g" % (i, j, v, w))
    for (i, j) in covered:  # every pixel: no spike, no hole
        v, w = pix(i, j)[0], want(i, j)
        d = abs(v - w) / max(w, 1e-3 * fr / math.pi * E)
        worst = max(worst, d)
    if worst > 0.01: bad.append("a covered pixel is %.3g off the cosine law (relative)" % worst)
    print("cosine law: 20 samples and %d covered pixels, worst relative deviation %.3g" % (len(covered), worst))
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

# the cosine law (fR = 0.6), one light of irradiance 2, and the default lights too
expect 0 "wrote L.exr (512x512)" -- "$VIEW" L.lss -o L.exr --light -0.4,0.5,1,2
check cosine L.exr 0.6 -0.4 0.5 1 2
expect 0 "" -- "$VIEW" L.lss -o L2.exr --light=0.9,-0.2,0.4,1
check cosine L2.exr 0.6 0.9 -0.2 0.4 1
# defaults: IN.lss.png, 512x512 RGB; --image-dim; --image-mul scales linear values
expect 0 "wrote L.lss.png (512x512)" -- "$VIEW" L.lss
check size L.lss.png 512 512 3
expect 0 "" -- "$VIEW" -q --image-dim 100 -o small.png L.lss
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
expect 2 "" -- "$VIEW" missing.lss
expect 2 "unknown option" -- "$VIEW" --nope L.lss
expect 2 "--image-dim" -- "$VIEW" --image-dim 0 L.lss
expect 2 "--light" -- "$VIEW" --light 1,2 L.lss
expect 2 "" -- "$VIEW"
expect 0 "--image-dim" -- "$VIEW" --help
[ ! -e t.png ] && ok || bad "an image of a refused LSS"

finish test_lssview
