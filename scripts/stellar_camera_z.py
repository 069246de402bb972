#!/usr/bin/python3
"""A stellar calibration's camera against the true lens (docs/stellar.md, "End to end through rendering and detection").

    scripts/stellar_camera_z.py CAL_DIR/calibration.json [--camera grids/builtin/orbigon.toml] [--plate ID]

Prints each plate-frame parameter of calibration.json (`platemeter calibrate stellar`), the truth, the stated sigma
and z = (value - truth) / sigma, and m_o, for every plate and every combination (the weighted mean). The truth is the camera definition's lens (the builtin orbigon: seed 001
Table 3, printed left-handed frame) turned into the plate frame as StellarCameraFromModel does: y and Phi_T
mirrored, xs/ys from the principal point (the values StellarPlate.RecoversTheTrueLensWithinThreeSigma prints as
its truth column). Standard library only (tomllib: Python 3.11).
"""
import argparse
import json
import math
import os
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))


def truth_plate_frame(toml_path, name):
    with open(toml_path, "rb") as f:
        cameras = tomllib.load(f)["camera"]
    lens = next((c["lens"] for c in cameras if c["name"] == name), None)
    if lens is None:
        raise SystemExit(f"{toml_path}: no camera {name}")
    if lens.get("model") != "orbigon-11":
        raise SystemExit(f"{toml_path}: only an orbigon-11 lens in seed 001's printed frame is handled")
    k = lens["coefficients"]
    xp = lens["principal_point_x_um"] * 1e-3
    yp = -lens["principal_point_y_um"] * 1e-3  # printed frame is left-handed (y down)
    return {
        "c_mm": lens["principal_distance_um"] * 1e-3,
        "xp_mm": xp,
        "yp_mm": yp,
        "xs_mm": k["xs_um"] * 1e-3 - xp,
        "ys_mm": -k["ys_um"] * 1e-3 - yp,
        "K1_per_m2": k["K1_per_m2"],
        "K2_per_m4": k["K2_per_m4"],
        "K3_per_m6": k["K3_per_m6"],
        "K4_per_m": k["K4_per_m"],
        "K5_per_m3": k["K5_per_m3"],
        "Phi_T_rad": -math.radians(k["Phi_T_deg"]),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("calibration")
    ap.add_argument("--camera", default=os.path.join(HERE, "..", "grids", "builtin", "orbigon.toml"))
    ap.add_argument("--camera-name", default="orbigon")
    ap.add_argument("--plate", default=None)
    args = ap.parse_args()
    truth = truth_plate_frame(args.camera, args.camera_name)
    with open(args.calibration) as f:
        cal = json.load(f)
    def table(cam):
        print(f"{'parameter':<11}{'value':>16}{'truth':>16}{'sigma':>12}{'z':>8}")
        for name, t in truth.items():
            v, s = cam[name]["value"], cam[name]["sigma"]
            d = v - t
            if name.startswith("Phi"):
                d = math.remainder(d, 2 * math.pi)
            print(f"{name:<11}{v:16.8g}{t:16.8g}{s:12.3g}{d / s:8.2f}")

    for plate in cal["plates"]:
        if args.plate and plate["id"] != args.plate:
            continue
        print(f"plate {plate['id']}: {plate.get('images')} images of {plate.get('catalog_stars')} catalog stars, "
              f"{plate.get('rejected_images')} rejected")
        table(plate["camera"]["plate_frame"])
        dof = (plate.get("statistics") or {}).get("degrees_of_freedom")
        print(f"m_o {plate['m_o']:.3f}" + (f" with {dof:.0f} dof" if dof else ""))
    for c in [] if args.plate else cal.get("combinations", []):
        print(f"combination {c['name']}: plates {', '.join(c.get('plates', []))}")
        table(c["camera"]["plate_frame"])
        print(f"m_0 {c['m_0']:.3f} with {c.get('degrees_of_freedom', float('nan')):.0f} dof")
    return 0


if __name__ == "__main__":
    sys.exit(main())
