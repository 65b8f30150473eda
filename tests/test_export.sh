#!/usr/bin/env bash
# lsqt-cl export: grid LSS files (the tutorial's Rough and Substr, a transmitting stack
# with --from-below, runs with bands: R, G, B and two wavelengths) as NetCDF, read back
# with xarray as a Python user would (and as Eradiate's tabulated BSDF checks it:
# dimension names, coordinates on linspace(0, 1, N) and 2 pi k / NPHI, units). Every
# value and standard error of brdf, btdf and their _below twins equals `lsqt-cl info
# --json --bsdf` at the direction the coordinates name (found by geometry, not by the
# exporter's index arithmetic), and R, T, delta_T per theta_o equal info's, band by band
# (channel k is band k; its labels and wavelength coordinate are the run's). A non-grid LSS, a wrong output name or kind, and output over input are
# errors (exit 2) that write nothing. Skipped (77) only where no Python has xarray and
# netCDF4 (tools/setup.sh installs Debian's).
# usage: test_export.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir

PY=
for p in /usr/bin/python3 python3; do
  if "$p" -c 'import xarray, netCDF4' 2>/dev/null; then PY=$p; break; fi
done
if [ -z "$PY" ]; then
  echo "test_export: skipped: no Python with xarray and netCDF4 (Debian: python3-xarray python3-netcdf4)"
  exit 77
fi

expect 0 "usage: lsqt-cl export FILE.lss -o OUT.nc" -- "$BIN" export --help

cp "$EX/tutorial/Rough.lsqt" R.lsqt
cp "$EX/tutorial/Substr.lsqt" S.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.5\nMedium eta=1.3 mus=2 mua=0.1 HenyeyGreensteinPhase g=0.5\nLayer z=-0.5 LambertianBsdf fR=0.2 fT=0.4\nMedium\n' > t.lsqt

# check.py NC INFO_JSON NO NI NPHI: the NetCDF against info --json --bsdf. With bands
# (info's "bands" > 1) every value of band k (info's lists) is channel k's, the channel
# dimension leads, and its labels and wavelengths are the run's; one band has no channel
# dimension, and at one wavelength (--wavelengths 550) a scalar wavelength coordinate.
cat > check.py <<'PY'
import json, math, sys
import numpy as np
import xarray as xr
nc, info_path, no, ni, nphi = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
d = xr.open_dataset(nc)
info = json.load(open(info_path))
p = []
nb, wl = info.get("bands", 1), info.get("wavelengths")
if nb > 1:
    labels = ["%.10gnm" % w for w in wl] if wl else ["R", "G", "B"] if nb == 3 else [str(k) for k in range(nb)]
    if d.sizes.get("channel") != nb: p.append("channel dimension %s, %d bands" % (d.sizes.get("channel"), nb))
    if list(d["channel"].values) != labels: p.append("channel labels %s, expected %s" % (d["channel"].values, labels))
    for v in d.data_vars:
        if d[v].dims[0] != "channel": p.append("%s dims %s: channel not first" % (v, d[v].dims))
    if wl is None and "wavelength" in d.variables: p.append("a wavelength coordinate without wavelengths")
    if wl is not None and ("wavelength" not in d["brdf"].coords or d["wavelength"].dtype != np.float64
                           or list(d["wavelength"].values) != wl or d["wavelength"].attrs.get("units") != "nm"):
        p.append("wavelength coordinate %s, expected %s nm" % (d["wavelength"].values if "wavelength" in d else None, wl))
elif "channel" in d.dims:
    p.append("one band with a channel dimension")
elif wl is None and "wavelength" in d.variables:
    p.append("one band without a wavelength has a wavelength coordinate")
elif wl is not None and ("wavelength" not in d["brdf"].coords or d["wavelength"].dims != ()
                         or [float(d["wavelength"])] != wl or d["wavelength"].attrs.get("units") != "nm"):
    p.append("one band at %s nm: wavelength %s" % (wl, d["wavelength"].values if "wavelength" in d else None))
bands = range(nb)
def band(x, k): return x[k] if nb > 1 else x  # info's value of band k
def chan(a, k): return a.isel(channel=k) if nb > 1 else a  # the NetCDF's
# what Eradiate's tabulated BSDF requires of its dataset (per band)
if set(chan(d["brdf"], 0).dims) != {"cos_theta_o", "phi_d", "cos_theta_i"}: p.append("brdf dims %s" % (d["brdf"].dims,))
for name, want in (("cos_theta_o", np.linspace(0, 1, no)), ("cos_theta_i", np.linspace(0, 1, ni)),
                   ("phi_d", np.linspace(0, 2 * np.pi, nphi, endpoint=False))):
    if d[name].size != want.size or not np.allclose(d[name].values, want, rtol=0, atol=1e-12):
        p.append("%s = %s, expected %s" % (name, d[name].values, want))
    if "units" not in d[name].attrs: p.append("%s has no units" % name)
if d["brdf"].attrs.get("units") != "sr-1": p.append("brdf units %r" % d["brdf"].attrs.get("units"))
if d.attrs.get("seed") != str(info["seed"]) or d.attrs.get("assembly") != info["assembly"] \
        or d.attrs.get("paths_per_slice") != str(info["paths"]) or d.attrs.get("grid") != "%d,%d,%d" % (no, ni, nphi):
    p.append("attributes %s" % {k: d.attrs.get(k) for k in ("seed", "paths_per_slice", "grid")})
def node(c):  # the direction simulated for a cos coordinate (the horizon at 0.001)
    return 0.001 if c == 0 else c
checked = 0
for side, suffix in ((False, ""), (True, "_below")):
    slices = [s for s in info["slices"] if s["from_below"] == side]
    if not slices:
        if "brdf" + suffix in d: p.append("brdf%s without slices from below" % suffix)
        continue
    by_cos = {round(math.cos(s["theta_o"]), 9): s for s in slices}
    for var, sign in (("brdf", 1), ("btdf", -1)):
        if not info["transmits"] and sign < 0:
            if var + suffix in d: p.append("btdf of a stack that transmits nothing")
            continue
        f, e = d[var + suffix], d[var + "_stderr" + suffix]
        for co in d["cos_theta_o"].values:
            s = by_cos.get(round(node(float(co)), 9))
            if s is None:
                p.append("no slice at cos_theta_o %g" % co); continue
            for ci in d["cos_theta_i"].values:
                c = node(float(ci)); st = math.sqrt(1 - c * c)
                for ph in d["phi_d"].values:
                    x, y, z = st * math.cos(ph), abs(st * math.sin(ph)), sign * c  # mirror symmetric in y
                    hit = [b for b in s["bsdf"] if abs(b[0] - x) < 2e-6 and abs(b[1] - y) < 2e-6 and abs(b[2] - z) < 2e-6]
                    if len(hit) < 1:
                        p.append("%s: no direction (%g %g %g) in info" % (var, x, y, z)); continue
                    for k in bands:
                        got = (float(chan(f, k).sel(cos_theta_o=co, cos_theta_i=ci, phi_d=ph)),
                               float(chan(e, k).sel(cos_theta_o=co, cos_theta_i=ci, phi_d=ph)))
                        want = [band(x, k) for x in hit[0][3:5]]
                        for g, w in zip(got, want):
                            if (w is None) != math.isnan(g) or (w is not None and abs(g - w) > 1e-8 * abs(w)):
                                p.append("%s%s band %d at cos_o %g cos_i %g phi %g: %r, info %r" % (var, suffix, k, co, ci, ph, got, want))
                        checked += 1
        for q in ("R", "T", "delta_T"):
            for k in bands:
                got = [float(v) for v in chan(d[q + suffix], k).values]
                want = [band(by_cos[round(node(float(co)), 9)][q], k) for co in d["cos_theta_o"].values]
                if any(abs(a - b) > 1e-8 * abs(b) for a, b in zip(got, want)): p.append("%s%s band %d %s, info %s" % (q, suffix, k, got, want))
if checked == 0: p.append("nothing compared")
if p: sys.exit("\n".join(p[:12]))
print("compared %d values" % checked)
PY

# Rough (reflection only), a 4 x 4 x 8 grid; the errors are known from 257 paths on.
"$BIN" -q -p 600 --grid 4,4,8 R.lsqt && "$BIN" export R.lsqt.lss -o R.nc -q && ok || bad "Rough: run and export"
"$BIN" info R.lsqt.lss --json R.json --bsdf > /dev/null
"$PY" check.py R.nc R.json 4 4 8 > out.txt 2>&1 && ok || bad "Rough NetCDF: $(cat out.txt)"
# Substr (a rough dielectric over a Lambertian floor), a 3 x 3 x 6 grid.
"$BIN" -q -p 600 --grid 3,3,6 S.lsqt && "$BIN" export S.lsqt.lss -o S.nc -q && ok || bad "Substr: run and export"
"$BIN" info S.lsqt.lss --json S.json --bsdf > /dev/null
"$PY" check.py S.nc S.json 3 3 6 > out.txt 2>&1 && ok || bad "Substr NetCDF: $(cat out.txt)"
# A transmitting stack with the slices from below: brdf, btdf, brdf_below, btdf_below.
"$BIN" -q -p 600 --grid 3,3,6 --from-below t.lsqt && "$BIN" export t.lsqt.lss -o t.nc && ok || bad "transmitting: run and export"
"$BIN" info t.lsqt.lss --json t.json --bsdf > /dev/null
"$PY" check.py t.nc t.json 3 3 6 > out.txt 2>&1 && ok || bad "transmitting NetCDF: $(cat out.txt)"
"$PY" -c 'import xarray as xr, sys; d = xr.open_dataset(sys.argv[1]); sys.exit(not all(v in d for v in ("btdf", "btdf_below", "brdf_below", "T_below")))' t.nc \
  && ok || bad "transmitting NetCDF lacks btdf or the _below variables"

# Bands: three unnamed ones (R, G, B: the example paint), and two with wavelengths on the
# transmitting stack with its slices from below; every channel is its band's.
cp "$EX/paint-rgb.lsqt" P.lsqt
"$BIN" -q -p 600 --grid 3,3,4 P.lsqt && expect 0 "wrote P.nc: brdf over (channel 3: R to B, cos_theta_i 3" -- \
  "$BIN" export P.lsqt.lss -o P.nc
"$BIN" info P.lsqt.lss --json P.json --bsdf > /dev/null
"$PY" check.py P.nc P.json 3 3 4 > out.txt 2>&1 && ok || bad "RGB NetCDF: $(cat out.txt)"
"$PY" -c 'import xarray as xr, sys; d = xr.open_dataset(sys.argv[1]); r = d.R.sel(channel="R", cos_theta_o=1.0)
sys.exit(not (r > d.R.sel(channel="G", cos_theta_o=1.0) > d.R.sel(channel="B", cos_theta_o=1.0)))' P.nc \
  && ok || bad "the red paint's R is not largest in red"
sed 's/fR=0.3 fT=0.5/fR=0.3,0.6 fT=0.5,0.2/' t.lsqt > tw.lsqt
"$BIN" -q -p 600 --grid 3,3,6 --from-below --wavelengths 450,650 tw.lsqt && "$BIN" export -q tw.lsqt.lss -o tw.nc \
  && ok || bad "wavelengths: run and export"
"$BIN" info tw.lsqt.lss --json tw.json --bsdf > /dev/null
"$PY" check.py tw.nc tw.json 3 3 6 > out.txt 2>&1 && ok || bad "NetCDF with wavelengths: $(cat out.txt)"
"$BIN" -q -p 600 --grid 3,3,6 --wavelengths 550 -o t1.raw --lss t1.lss t.lsqt && "$BIN" export -q t1.lss -o t1.nc \
  && ok || bad "one band at 550 nm: run and export"
"$BIN" info t1.lss --json t1.json --bsdf > /dev/null
"$PY" check.py t1.nc t1.json 3 3 6 > out.txt 2>&1 && ok || bad "NetCDF of one band at 550 nm: $(cat out.txt)"
"$PY" -c 'import xarray as xr, sys; d = xr.open_dataset(sys.argv[1])
sys.exit(not (list(d.btdf_below.dims) == ["channel", "cos_theta_i", "phi_d", "cos_theta_o"]
              and float(d.brdf.sel(channel="650nm").wavelength) == 650.0))' tw.nc \
  && ok || bad "wavelengths: btdf_below's dimensions or sel(channel=\"650nm\")"

# Errors: nothing written, an existing file kept.
"$BIN" -q -p 300 -wo 4 -wi 16 --wi-spread --lss s.lss -o s.raw R.lsqt
cp R.nc keep.nc
expect 2 "'s.lss' is not on a grid (its incident directions were chosen by --wi-spread)" -- "$BIN" export s.lss -o keep.nc
cmp -s R.nc keep.nc && ok || bad "a refused export changed the existing output"
expect 2 "must end in .nc" -- "$BIN" export R.lsqt.lss -o R.txt
mkdir dir.nc
expect 2 "'dir.nc' is a directory: NetCDF is written to a regular file" -- "$BIN" export R.lsqt.lss -o dir.nc
cp R.lsqt.lss same.nc
expect 2 "would replace the input" -- "$BIN" export same.nc -o same.nc
expect 2 "usage: lsqt-cl export" -- "$BIN" export R.lsqt.lss
expect 2 "unknown option '--rgbx'" -- "$BIN" export R.lsqt.lss -o x.nc --rgbx
expect 2 "'missing.lss'" -- "$BIN" export missing.lss -o x.nc
[ ! -e x.nc ] && [ ! -e R.txt ] && ok || bad "a refused export wrote a file"
ls ./*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok

# A write that fails inside netCDF, past the free-space check (a file-size limit: EFBIG):
# exit 1 naming the file and the cause, no crash (the failed file is abandoned, not
# closed: HDF5 crashed closing it or at exit), no temporary, the previous file whole.
cp R.nc big.nc && cp R.nc keep_big.nc
expect 1 "cannot write 'big.nc' (enddef): File too large" -- bash -c "trap '' XFSZ; ulimit -f 8; exec \"\$0\" export R.lsqt.lss -o big.nc" "$BIN"
cmp -s big.nc keep_big.nc && ok || bad "a failed netCDF write changed the previous file"
ls ./*.tmp.* >/dev/null 2>&1 && bad "temporary files left by the failed netCDF write" || ok

# A full file system (a small tmpfs, as root): exit 1 naming the cause, no temporary, the
# previous file whole, and no crash (HDF5 met a full disk badly).
if cli_tmpfs small 1m; then
  expect 0 "" -- "$BIN" export R.lsqt.lss -o small/x.nc -q
  cp small/x.nc keep_small.nc
  head -c "$(($(df -B1 --output=avail small | tail -1) - 8192))" /dev/zero >small/filler
  expect 1 "cannot write 'small/x.nc': No space left on device" -- "$BIN" export R.lsqt.lss -o small/x.nc
  cmp -s small/x.nc keep_small.nc && ok || bad "a full disk changed the previous NetCDF"
  [ -z "$(find small -name '*.tmp.*')" ] && ok || bad "temporaries left on the full file system"
else
  echo "skip: cannot mount a tmpfs here (not root?): the full file system check skipped"
fi
finish test_export
