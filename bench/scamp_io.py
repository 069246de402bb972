#!/usr/bin/python3
"""FITS-LDAC input for SCAMP and the evaluation of its solution, for
bench/bench_stellar_scamp.cpp (Debian python3-astropy).

  scamp_io.py write STARS.csv REF.csv HEADER.txt OUT_DIR
      STARS.csv: x_px,y_px,sigma_px,flux   (the plate's identified images)
      REF.csv:   ra_deg,dec_deg,sigma_deg,mag (their reference places)
      HEADER.txt: FITS cards "KEY = value" of the plate's initial WCS
      writes OUT_DIR/plate.cat and OUT_DIR/reference.cat (FITS-LDAC)
  scamp_io.py evaluate PLATE.head HEADER.txt GRID.csv SCAMP.xml OUT.csv STATS.txt
      the world coordinates (deg) of GRID.csv's x_px,y_px through SCAMP's
      solution (HEADER.txt updated by PLATE.head: TAN + TPV polynomial), and
      in STATS.txt the number of detections SCAMP matched to the reference
      (AstromNDets_Reference of its XML report).
"""
import csv
import sys

import warnings

import numpy as np
from astropy.io import fits
from astropy.io.votable import parse as parse_votable
from astropy.wcs import WCS, FITSFixedWarning

warnings.simplefilter("ignore", FITSFixedWarning)  # astropy's DATE-OBS note from MJD-OBS


def header_from_text(path):
    header = fits.Header()
    for line in open(path):
        line = line.strip()
        if not line or line.startswith("END"):
            continue
        header.append(fits.Card.fromstring(line.ljust(80)))
    return header


def ldac(objects, image_header):
    # One row holding the whole header, 80 characters per card (TDIM1 = (80, N)).
    text = image_header.tostring(sep="", endcard=True, padding=True)  # whole 2880-byte blocks, as SExtractor writes
    cards = len(text) // 80
    card_rows = np.array([[text[i:i + 80] for i in range(0, len(text), 80)]])
    imhead = fits.BinTableHDU.from_columns(
        [fits.Column(name="Field Header Card", format="%dA" % (80 * cards), array=card_rows, dim="(80, %d)" % cards)])
    imhead.header["EXTNAME"] = "LDAC_IMHEAD"
    objects.header["EXTNAME"] = "LDAC_OBJECTS"
    return fits.HDUList([fits.PrimaryHDU(), imhead, objects])


def write_ldac(hdus, path):
    """Writes the file, then turns the NULs astropy pads the header cards with
    into the spaces FITS cards have (SCAMP looks for a space-padded END card)."""
    hdus.writeto(path, overwrite=True)
    with fits.open(path) as f:
        offset, size = f[1]._data_offset, f[1]._data_size
    with open(path, "r+b") as f:
        f.seek(offset)
        block = f.read(size)
        f.seek(offset)
        f.write(block.replace(b"\0", b" "))


def read_csv(path):
    rows = list(csv.DictReader(open(path)))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def write(stars_csv, ref_csv, header_txt, out_dir):
    header = header_from_text(header_txt)
    s = read_csv(stars_csv)
    n = len(s["x_px"])
    objects = fits.BinTableHDU.from_columns([
        fits.Column(name="NUMBER", format="J", array=np.arange(1, n + 1)),
        fits.Column(name="XWIN_IMAGE", format="D", array=s["x_px"]),
        fits.Column(name="YWIN_IMAGE", format="D", array=s["y_px"]),
        fits.Column(name="ERRAWIN_IMAGE", format="E", array=s["sigma_px"]),
        fits.Column(name="ERRBWIN_IMAGE", format="E", array=s["sigma_px"]),
        fits.Column(name="ERRTHETAWIN_IMAGE", format="E", array=np.zeros(n)),
        fits.Column(name="FLUX_AUTO", format="E", array=s["flux"]),
        fits.Column(name="FLUXERR_AUTO", format="E", array=s["flux"] * 0.01),
        fits.Column(name="FLUX_RADIUS", format="E", array=np.full(n, 1.2)),
        fits.Column(name="ELONGATION", format="E", array=np.ones(n)),
        fits.Column(name="FLAGS", format="I", array=np.zeros(n, dtype=np.int16)),
    ])
    write_ldac(ldac(objects, header), out_dir + "/plate.cat")
    r = read_csv(ref_csv)
    m = len(r["ra_deg"])
    reference = fits.BinTableHDU.from_columns([
        fits.Column(name="X_WORLD", format="D", array=r["ra_deg"]),
        fits.Column(name="Y_WORLD", format="D", array=r["dec_deg"]),
        fits.Column(name="ERRA_WORLD", format="E", array=r["sigma_deg"]),
        fits.Column(name="ERRB_WORLD", format="E", array=r["sigma_deg"]),
        fits.Column(name="ERRTHETA_WORLD", format="E", array=np.zeros(m)),
        fits.Column(name="MAG", format="E", array=r["mag"]),
        fits.Column(name="MAGERR", format="E", array=np.full(m, 0.01)),
        fits.Column(name="OBSDATE", format="D", array=np.full(m, 2000.0)),
        fits.Column(name="FLAGS", format="I", array=np.zeros(m, dtype=np.int16)),
    ])
    write_ldac(ldac(reference, header), out_dir + "/reference.cat")


def matched_detections(xml_path):
    for table in parse_votable(xml_path).iter_tables():
        if table.name == "FGroups":
            return int(table.array["AstromNDets_Reference"][0])
    return 0


def evaluate(head_path, header_txt, grid_csv, xml_path, out_csv, stats_txt):
    header = header_from_text(header_txt)
    for line in open(head_path):
        line = line.rstrip("\n")
        if line.startswith(("END", "COMMENT", "HISTORY")) or "=" not in line[:10]:
            continue
        card = fits.Card.fromstring(line.ljust(80))
        header[card.keyword] = card.value
    header["CTYPE1"], header["CTYPE2"] = "RA---TPV", "DEC--TPV"
    wcs = WCS(header)
    g = read_csv(grid_csv)
    world = wcs.all_pix2world(np.c_[g["x_px"], g["y_px"]], 1)
    with open(out_csv, "w") as f:
        f.write("ra_deg,dec_deg\n")
        for ra, dec in world:
            f.write("%.12f,%.12f\n" % (ra, dec))
    with open(stats_txt, "w") as f:
        f.write("%d\n" % matched_detections(xml_path))


if __name__ == "__main__":
    if sys.argv[1] == "write":
        write(*sys.argv[2:6])
    elif sys.argv[1] == "evaluate":
        evaluate(*sys.argv[2:8])
    else:
        sys.exit("usage: scamp_io.py write|evaluate ...")
