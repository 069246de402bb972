#!/usr/bin/python3
"""Apparent (observed) places: platemeter against astropy (docs/apparent-places.md).

For each of three sites and dates, 200 seeded stars spread over the sky above
20 deg altitude (ICRS position at their own catalog epoch, proper motion,
parallax, radial velocity) go through

  platemeter stars apparent   (ERFA: eraApco13, eraAtciq, eraAtioq; C++)
  astropy                     SkyCoord.apply_space_motion(new_obstime), then ICRS -> AltAz
                              and ICRS -> HADec (erfa.apco, astropy's own atciqz, erfa.atioq)

with the same site, UTC instant, pressure, temperature, relative humidity and
wavelength, and the same Earth orientation: UT1-UTC and polar motion are read
once from astropy's bundled IERS-B table (EOP C04, no download) and given to
both sides (platemeter --ut1-utc-s/--xp-arcsec/--yp-arcsec; astropy
Time.delta_ut1_utc and the same table as earth_orientation_table).

Compared: the observed direction (azimuth, altitude) as an angular separation,
and the observed hour angle and declination, once refracted and once in vacuum
(pressure 0 on both sides). Every star must agree within --tolerance-arcsec
(0.05"); the max and RMS separation per site are printed. Exit 0 when all
agree, 1 when any star does not, 2 for a setup problem (no astropy, no
platemeter command).

Debian's python3-astropy (scripts/setup) is used through /usr/bin/python3; no
network access is attempted (iers.conf.auto_download and
astropy.utils.data.conf.allow_internet are off).
"""
import argparse
import csv
import io
import math
import os
import subprocess
import sys
import tempfile
import warnings

ARCSEC_PER_RAD = 180.0 * 3600.0 / math.pi

# The sites and instants. Beltsville: seed 001 ("All stellar exposures were
# obtained at the NOS calibration test site located in Beltsville, Maryland",
# 1972, zenith pointing, GMT); the seed gives neither coordinates nor dates, so
# both are approximate and chosen (a moonless-season night in 1972). The other
# two span latitude (67 N, 30 S), height (to 2207 m), temperature (-25 to
# +12 C), wavelength and epoch (28 yr before to 21 yr after J2000).
SITES = [
    dict(name="beltsville-1972", lat_deg=39.03, lon_deg=-76.93, height_m=50.0,
         utc="1972-10-10T03:00:00", pressure_hpa=1010.0, temperature_degC=8.0,
         humidity=0.7, wavelength_um=0.50),
    dict(name="ctio-2001", lat_deg=-30.169, lon_deg=-70.806, height_m=2207.0,
         utc="2001-04-20T04:00:00", pressure_hpa=780.0, temperature_degC=12.0,
         humidity=0.2, wavelength_um=0.45),
    dict(name="sodankyla-2021", lat_deg=67.367, lon_deg=26.633, height_m=180.0,
         utc="2021-01-15T22:00:00", pressure_hpa=1000.0, temperature_degC=-25.0,
         humidity=0.85, wavelength_um=0.65),
]


def fail_setup(message):
    print(f"compare_astropy: {message}", file=sys.stderr)
    sys.exit(2)


def import_astropy():
    try:
        from astropy.utils import iers
        from astropy.utils.data import conf as data_conf
    except ImportError as e:
        fail_setup(f"astropy is not importable by {sys.executable} ({e}); run scripts/setup (python3-astropy)")
    iers.conf.auto_download = False      # never fetch IERS-A / leap seconds
    data_conf.allow_internet = False
    table = iers.IERS_B.open(iers.IERS_B_FILE)  # bundled EOP C04 (IERS-B)
    iers.earth_orientation_table.set(table)
    import astropy
    return astropy, iers


def generate_stars(rng_seed, site, count):
    """`count` stars whose observed places at the site and instant lie above
    20 deg: directions uniform on the sky cap above 21 deg (vacuum, at the
    instant), then catalog data around them. Returns a list of dicts."""
    import numpy as np
    import astropy.units as u
    from astropy.coordinates import AltAz, EarthLocation, SkyCoord
    from astropy.time import Time

    rng = np.random.default_rng(rng_seed)
    location = EarthLocation.from_geodetic(site["lon_deg"] * u.deg, site["lat_deg"] * u.deg,
                                           site["height_m"] * u.m)
    t = Time(site["utc"], scale="utc")
    n_pole, n_fast = 2, 5
    n_random = count - n_pole
    # Uniform on the cap alt >= 21 deg: sin(alt) uniform.
    sin_alt = rng.uniform(math.sin(math.radians(21.0)), 1.0, n_random)
    az = rng.uniform(0.0, 360.0, n_random)
    altaz = SkyCoord(az=az * u.deg, alt=np.degrees(np.arcsin(sin_alt)) * u.deg,
                     frame=AltAz(obstime=t, location=location))
    icrs = altaz.transform_to("icrs")
    ra = list(icrs.ra.deg)
    dec = list(icrs.dec.deg)
    # Two stars within a degree of the celestial pole above the horizon
    # (mu_alpha* near the pole: RA moves fast).
    pole_sign = 1.0 if site["lat_deg"] >= 0 else -1.0
    for _ in range(n_pole):
        ra.append(rng.uniform(0.0, 360.0))
        dec.append(pole_sign * rng.uniform(89.0, 89.99))

    stars = []
    for i in range(count):
        fast = i < n_fast  # nearby, fast stars: proper motions of 5-25"/yr
        if fast:
            parallax_mas = rng.uniform(300.0, 800.0)
            v_tan = rng.uniform(80.0, 150.0)
            angle = rng.uniform(0.0, 2.0 * math.pi)
            v_e, v_n = v_tan * math.sin(angle), v_tan * math.cos(angle)
            rv = rng.normal(0.0, 80.0)
        elif rng.uniform() < 0.1:
            # 10 %: no parallax (as many catalog stars), proper motion alone, no radial velocity.
            parallax_mas, rv = 0.0, 0.0
            v_e, v_n = rng.normal(0.0, 50.0 * 4.740470446, 2)  # pm sigma 50 mas/yr below
        else:
            parallax_mas = 10.0 ** rng.uniform(math.log10(0.5), math.log10(800.0))
            sigma = 150.0 if rng.uniform() < 0.1 else 30.0  # 10 % halo stars
            v_e, v_n = rng.normal(0.0, sigma, 2)
            rv = 0.0 if rng.uniform() < 0.4 else rng.normal(0.0, sigma)
        # km/s -> mas/yr: mu = v / (4.740470 km/s per au/yr) * parallax (1 mas for no parallax)
        pm_ra = v_e * max(parallax_mas, 1.0) / 4.740470446
        pm_dec = v_n * max(parallax_mas, 1.0) / 4.740470446
        epoch = float(rng.choice([2000.0, 2000.0, 1991.25, 2016.0]))
        stars.append(dict(id=i + 1, ra_deg=ra[i] % 360.0, dec_deg=dec[i], pm_ra_mas_yr=pm_ra,
                          pm_dec_mas_yr=pm_dec, parallax_mas=parallax_mas, rv_km_s=rv,
                          epoch_jyear=epoch, v_mag=rng.uniform(0.0, 8.0)))
    return stars


def write_star_list(stars, path):
    fields = ["id", "ra_deg", "dec_deg", "pm_ra_mas_yr", "pm_dec_mas_yr", "parallax_mas",
              "rv_km_s", "epoch_jyear", "v_mag"]
    with open(path, "w") as f:
        f.write("# seeded test stars for compare_astropy.py (ICRS at epoch_jyear, TDB)\n")
        f.write(",".join(fields) + "\n")
        for s in stars:
            f.write(",".join(repr(s[k]) if k != "id" else str(s[k]) for k in fields) + "\n")


def run_platemeter(platemeter, star_list, site, eop, refraction):
    cmd = [platemeter, "stars", "apparent", "--stars", star_list,
           "--utc", site["utc"] + "Z",
           "--lat-deg", repr(site["lat_deg"]), "--lon-deg", repr(site["lon_deg"]),
           "--height-m", repr(site["height_m"]),
           "--pressure-hpa", repr(site["pressure_hpa"] if refraction else 0.0),
           "--temperature-degc", repr(site["temperature_degC"]),
           "--humidity", repr(site["humidity"]), "--wavelength-um", repr(site["wavelength_um"]),
           "--ut1-utc-s", repr(eop["dut1_s"]), "--xp-arcsec", repr(eop["xp_arcsec"]),
           "--yp-arcsec", repr(eop["yp_arcsec"])]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        fail_setup(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr.strip()}")
    rows = [line for line in proc.stdout.splitlines() if line and not line.startswith("#")]
    places = {}
    for r in csv.DictReader(io.StringIO("\n".join(rows))):
        places[int(r["id"])] = {k: float(v) for k, v in r.items()}
    return places


def astropy_places(stars, site, eop, refraction):
    """astropy's observed places: dict id -> (az, alt, ha, dec) in degrees, plus
    the largest proper-motion displacement (arcsec) applied."""
    import numpy as np
    import astropy.units as u
    from astropy.coordinates import AltAz, Distance, EarthLocation, HADec, SkyCoord
    from astropy.time import Time

    location = EarthLocation.from_geodetic(site["lon_deg"] * u.deg, site["lat_deg"] * u.deg,
                                           site["height_m"] * u.m)
    t = Time(site["utc"], scale="utc")
    t.delta_ut1_utc = eop["dut1_s"]  # the value given to platemeter, explicitly
    weather = dict(pressure=(site["pressure_hpa"] if refraction else 0.0) * u.hPa,
                   temperature=site["temperature_degC"] * u.deg_C,
                   relative_humidity=site["humidity"] * u.one,
                   obswl=site["wavelength_um"] * u.micron)
    out = {}
    max_motion_arcsec = 0.0
    groups = sorted({(s["epoch_jyear"], s["parallax_mas"] > 0.0) for s in stars})
    for epoch, has_parallax in groups:
        group = [s for s in stars if s["epoch_jyear"] == epoch and (s["parallax_mas"] > 0.0) == has_parallax]
        col = lambda k: np.array([s[k] for s in group])
        common = dict(ra=col("ra_deg") * u.deg, dec=col("dec_deg") * u.deg,
                      pm_ra_cosdec=col("pm_ra_mas_yr") * u.mas / u.yr,
                      pm_dec=col("pm_dec_mas_yr") * u.mas / u.yr,
                      obstime=Time(epoch, format="jyear", scale="tdb"), frame="icrs")
        if has_parallax:
            catalog = SkyCoord(distance=Distance(parallax=col("parallax_mas") * u.mas),
                               radial_velocity=col("rv_km_s") * u.km / u.s, **common)
        else:
            catalog = SkyCoord(**common)  # no distance: a direction with proper motion
        with warnings.catch_warnings():
            if not has_parallax:
                # No distance: pmsafe assumes a minimum parallax and says so ("distance overridden").
                import erfa
                warnings.simplefilter("ignore", erfa.ErfaWarning)
            moved = catalog.apply_space_motion(new_obstime=t)  # erfa.pmsafe, catalog epoch -> instant
        max_motion_arcsec = max(max_motion_arcsec, float(np.max(catalog.separation(moved).arcsec)))
        # The moved position (with its distance for parallax), without velocities.
        if has_parallax:
            at_instant = SkyCoord(ra=moved.ra, dec=moved.dec, distance=moved.distance, frame="icrs")
        else:
            at_instant = SkyCoord(ra=moved.ra, dec=moved.dec, frame="icrs")
        altaz = at_instant.transform_to(AltAz(obstime=t, location=location, **weather))
        hadec = at_instant.transform_to(HADec(obstime=t, location=location, **weather))
        for k, s in enumerate(group):
            out[s["id"]] = (altaz.az.deg[k], altaz.alt.deg[k], hadec.ha.deg[k], hadec.dec.deg[k])
    return out, max_motion_arcsec


def unit(lon_deg, lat_deg):
    lon, lat = math.radians(lon_deg), math.radians(lat_deg)
    return (math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat))


def separation_arcsec(lon1, lat1, lon2, lat2):
    a, b = unit(lon1, lat1), unit(lon2, lat2)
    cross = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    dot = sum(x * y for x, y in zip(a, b))
    return math.atan2(math.sqrt(sum(c * c for c in cross)), dot) * ARCSEC_PER_RAD


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--platemeter", required=True, help="the platemeter binary")
    parser.add_argument("--stars", type=int, default=200, help="stars per site")
    parser.add_argument("--seed", type=int, default=20240601, help="random seed (per site: seed + index)")
    parser.add_argument("--tolerance-arcsec", type=float, default=0.05)
    parser.add_argument("--work-dir", help="keep the star lists here (default: a temporary folder)")
    args = parser.parse_args()

    astropy, iers = import_astropy()
    try:
        probe = subprocess.run([args.platemeter, "stars", "apparent", "--help"], capture_output=True, text=True)
    except OSError as e:
        fail_setup(f"cannot run {args.platemeter}: {e}")
    if probe.returncode != 0 or "--lat-deg" not in probe.stdout:
        fail_setup(f"{args.platemeter} has no 'stars apparent' command (cli::RegisterStarsCommand not called "
                   f"in cli/main.cpp?)")
    if args.work_dir:
        os.makedirs(args.work_dir, exist_ok=True)
        return compare(args, astropy, iers, args.work_dir)
    with tempfile.TemporaryDirectory(prefix="platemeter-astropy-") as work_dir:
        return compare(args, astropy, iers, work_dir)


def compare(args, astropy, iers, work_dir):
    from astropy.time import Time
    from astropy.coordinates.builtin_frames.utils import get_polar_motion

    print(f"astropy {astropy.__version__} ({os.path.dirname(astropy.__file__)}), "
          f"IERS-B {os.path.basename(iers.IERS_B_FILE)}; platemeter {args.platemeter}")
    print(f"{args.stars} stars per site above 20 deg; tolerance {args.tolerance_arcsec}\" per star")
    all_ok = True
    for index, site in enumerate(SITES):
        t = Time(site["utc"], scale="utc")
        with warnings.catch_warnings():
            # The bundled leap-second file is past its expiry date; no download is wanted (none since 2017).
            warnings.simplefilter("ignore", iers.IERSStaleWarning)
            xp_rad, yp_rad = get_polar_motion(t)
            eop = dict(dut1_s=float(t.delta_ut1_utc), xp_arcsec=float(xp_rad) * ARCSEC_PER_RAD,
                       yp_arcsec=float(yp_rad) * ARCSEC_PER_RAD)
            stars = generate_stars(args.seed + index, site, args.stars)
            star_list = os.path.join(work_dir, f"stars-{site['name']}.csv")
            write_star_list(stars, star_list)
            epochs = sorted({s["epoch_jyear"] for s in stars})
            mix = ", ".join(f"J{e:g}: {sum(s['epoch_jyear'] == e for s in stars)}" for e in epochs)
            no_px = sum(s["parallax_mas"] == 0.0 for s in stars)
            print(f"\n{site['name']}: lat {site['lat_deg']} lon {site['lon_deg']} h {site['height_m']} m, "
                  f"{site['utc']}Z, {site['pressure_hpa']} hPa {site['temperature_degC']} C "
                  f"RH {site['humidity']} {site['wavelength_um']} um; IERS-B UT1-UTC {eop['dut1_s']:+.6f} s, "
                  f"xp {eop['xp_arcsec']:+.6f}\" yp {eop['yp_arcsec']:+.6f}\"")
            print(f"  stars: {len(stars)} ({no_px} without parallax, {sum(s['rv_km_s'] != 0.0 for s in stars)} "
                  f"with a radial velocity); catalog epochs {mix}; list {star_list}")
            refracted_alt = None
            for refraction in (True, False):
                ours = run_platemeter(args.platemeter, star_list, site, eop, refraction)
                theirs, max_motion = astropy_places(stars, site, eop, refraction)
                missing = [s["id"] for s in stars if s["id"] not in ours]
                if missing:
                    print(f"  platemeter returned no place for stars {missing[:10]}")
                    all_ok = False
                sep_altaz, sep_hadec, worst = [], [], (0.0, None)
                d_alt, d_az = [], []
                for s in stars:
                    if s["id"] not in ours:
                        continue
                    p, (az, alt, ha, dec) = ours[s["id"]], theirs[s["id"]]
                    sa = separation_arcsec(p["az_deg"], p["alt_deg"], az, alt)
                    sh = separation_arcsec(p["ha_deg"], p["dec_obs_deg"], ha, dec)
                    sep_altaz.append(sa)
                    sep_hadec.append(sh)
                    d_alt.append(abs(p["alt_deg"] - alt) * 3600.0)
                    d_az.append(abs(math.remainder(p["az_deg"] - az, 360.0)) * 3600.0 * math.cos(math.radians(alt)))
                    if max(sa, sh) > worst[0]:
                        worst = (max(sa, sh), s)
                if refraction:
                    refracted_alt = {i: theirs[i][1] for i in theirs}
                    min_alt = min(v[1] for v in theirs.values())
                    if min_alt < 20.0:
                        print(f"  a test star is at {min_alt:.3f} deg, below 20 deg (generator error)")
                        all_ok = False
                else:
                    lift = max(abs(refracted_alt[i] - theirs[i][1]) * 3600.0 for i in theirs)
                rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v))
                label = "refracted" if refraction else "vacuum   "
                ok = max(sep_altaz) <= args.tolerance_arcsec and max(sep_hadec) <= args.tolerance_arcsec
                all_ok = all_ok and ok and not missing
                print(f"  {label} az/alt: max {max(sep_altaz):.6f}\" rms {rms(sep_altaz):.6f}\" "
                      f"(|dalt| max {max(d_alt):.6f}\", |daz cos alt| max {max(d_az):.6f}\"); "
                      f"ha/dec: max {max(sep_hadec):.6f}\" rms {rms(sep_hadec):.6f}\"  "
                      f"{'ok' if ok else 'FAIL'}")
                if not ok:
                    print(f"    worst star: {worst[1]}")
            print(f"  effects exercised: proper motion up to {max_motion:.1f}\" (catalog epoch -> instant), "
                  f"refraction up to {lift:.1f}\"")
    print("\nall stars agree" if all_ok else "\nSOME STARS DISAGREE")
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
