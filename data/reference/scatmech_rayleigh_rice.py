#!/usr/bin/env python3
"""Reference values of the Rayleigh-Rice BRDF of a conductor from NIST SCATMECH.

Writes scatmech_rayleigh_rice.json beside this file: the Mueller BRDF of
SCATMECH's `Microroughness_BRDF_Model` (first-order vector perturbation
theory, T. A. Germer, Appl. Opt. 36, 8798 (1997)) for reflection from a
conductor with a K-correlation PSD, at in-plane forward and backward and
out-of-plane geometries with theta to 89 deg, for several metals and
wavelengths:

* m00 -- unpolarised incidence, unpolarised detection (M00);
* s, p -- s- or p-polarised incidence, both scattered polarisations summed
  (M00 + M01 and M00 - M01 in SCATMECH's "psps" coordinates; which sign is s
  is checked below against the Fresnel reflectances at the mirror).

Conventions (SCATMECH): lengths in um; the specular direction is
theta_s = theta_i, phi_s = 0; the ABC PSD is A / (1 + (B f)^2)^(C/2) with f in
cycles/um. lustre's K-correlation PSD (docs/physics.md sec. 2, rad/um) is
the same function with B = 2 pi Lc, C = gamma + 1 and
A = 2 pi Lc^2 (gamma - 1) sigma^2. The metals' n, k are rows of lustre's
data/spectra/ior_*.csv (no interpolation), recorded per case.

Run:  python3 -m venv venv && venv/bin/pip install pyscatmech==0.1.10
      venv/bin/python scatmech_rayleigh_rice.py
"""

import csv
import json
import math
import os
import cmath

from pySCATMECH.brdf import BRDF_Model

HERE = os.path.dirname(os.path.abspath(__file__))
SPECTRA = os.path.join(HERE, "..", "spectra")

# (lustre metal name, csv file, wavelengths in nm that are rows of the file)
METALS = [
    ("au", "ior_Au.csv", [450.9, 659.5]),
    ("al", "ior_Al.csv", [413.28, 688.81]),
    ("cu", "ior_Cu.csv", [548.6]),
    ("ag", "ior_Ag.csv", [495.9]),
    ("cr", "ior_Cr.csv", [756.0]),
]

# (sigma um, Lc um, gamma)
SURFACES = [
    (0.001, 10.0, 3.5),
    (0.01, 2.0, 2.0),
    (0.005, 0.5, 1.5),
    (0.002, 50.0, 4.0),
]

THETA_I = [0.0, 30.0, 60.0, 80.0, 89.0]
THETA_S = [0.0, 10.0, 45.0, 70.0, 85.0, 89.0]
PHI_S = [0.0, 30.0, 90.0, 135.0, 180.0]


def nk_rows(name):
    with open(os.path.join(SPECTRA, name), newline="") as f:
        rows = list(csv.reader(f))[1:]
    return {float(r[0]): (float(r[1]), float(r[2])) for r in rows}


def model(lam_um, n, k, sigma, lc, gamma):
    m = BRDF_Model("Microroughness_BRDF_Model")
    b = 2.0 * math.pi * lc
    a = 2.0 * math.pi * lc * lc * (gamma - 1.0) * sigma * sigma
    m.setParameters({
        "lambda": repr(lam_um),
        "substrate": "(%r,%r)" % (n, k),
        "type": "0",
        "psd": "ABC_PSD_Function",
        "psd.A": repr(a),
        "psd.B": repr(b),
        "psd.C": repr(gamma + 1.0),
    })
    return m


def fresnel_sp(n, k, cos_t):
    e = complex(n, k) ** 2
    a = cmath.sqrt(e - (1.0 - cos_t * cos_t))
    rs = abs((cos_t - a) / (cos_t + a)) ** 2
    rp = abs((e * cos_t - a) / (e * cos_t + a)) ** 2
    return rs, rp


def main():
    rows = []
    case = 0
    for metal, csv_name, lams in METALS:
        table = nk_rows(csv_name)
        for lam in lams:
            n, k = table[lam]
            sigma, lc, gamma = SURFACES[case % len(SURFACES)]
            case += 1
            m = model(lam / 1000.0, n, k, sigma, lc, gamma)
            # Which Stokes sign is s: at the mirror, RR is proportional to
            # the Fresnel reflectance of the incident polarisation.
            t = math.radians(60.0)
            mm = m.MuellerBRDF(t, t, 0.0)
            rs, rp = fresnel_sp(n, k, math.cos(t))
            ratio = (mm[0][0] + mm[0][1]) / (mm[0][0] - mm[0][1])
            assert abs(ratio / (rs / rp) - 1.0) < 1e-9, (ratio, rs / rp)
            for ti in THETA_I:
                for ts in THETA_S:
                    for ps in PHI_S:
                        mm = m.MuellerBRDF(math.radians(ti), math.radians(ts),
                                           math.radians(ps))
                        m00, m01 = mm[0][0], mm[0][1]
                        rows.append({
                            "metal": metal, "lambda_nm": lam, "n": n, "k": k,
                            "sigma_um": sigma, "lc_um": lc, "gamma": gamma,
                            "theta_i_deg": ti, "theta_s_deg": ts, "phi_s_deg": ps,
                            "m00": m00, "s": m00 + m01, "p": m00 - m01,
                        })
    out = {
        "source": "NIST SCATMECH via pySCATMECH 0.1.10, Microroughness_BRDF_Model "
                  "(reflection, type 0), ABC_PSD_Function",
        "script": "data/reference/scatmech_rayleigh_rice.py",
        "units": "BRDF in 1/sr; lengths in um; angles in degrees; specular at "
                 "theta_s = theta_i, phi_s = 0 (lustre: phi_o = phi_s + 180 deg with "
                 "wi at azimuth 0)",
        "rows": rows,
    }
    # One row per line: readable diffs, a third of the size of indent=1.
    head = json.dumps({k: v for k, v in out.items() if k != "rows"}, indent=1)
    body = ",\n".join(json.dumps(r) for r in rows)
    with open(os.path.join(HERE, "scatmech_rayleigh_rice.json"), "w") as f:
        f.write(head[:-2] + ',\n "rows": [\n' + body + "\n ]\n}\n")
    print(len(rows), "rows")


if __name__ == "__main__":
    main()
