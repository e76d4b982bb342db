"""Prints the RGB complex indices of refraction (eta, k) that Mitsuba 3 (scalar_rgb) uses for each
named conductor material, as the Rust table in src/material/conductor_presets.rs.

Mitsuba tabulates measured spectral eta/k per material and reduces them to linear sRGB in its RGB
variants; neumann uses the same reduced values so that `<string name="material" value="Au"/>`
renders as it does in Mitsuba. Run in a venv outside the repository:

    python3 -m venv ~/mitsuba-venv && ~/mitsuba-venv/bin/pip install mitsuba
    ~/mitsuba-venv/bin/python tools/mitsuba/conductor_presets.py
"""
import mitsuba as mi

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)  # out-of-gamut clamping warnings would interleave with the table
MATERIALS = ("a-C Ag Al AlAs AlSb Au Be Cr CsI Cu Cu2O CuO d-C Hg HgTe Ir K Li MgO Mo Na_palik Nb "
             "Ni_palik Rh Se_palik SiC SnTe Ta Te ThF4 TiC TiN TiO2 VC V_palik VN W").split()

for name in MATERIALS:
    params = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
    eta, k = params["eta.value"], params["k.value"]
    fmt = lambda c: ", ".join(f"{max(float(x), 0.0):.6}" for x in c)
    print(f'    ("{name}", [{fmt(eta)}], [{fmt(k)}]),')
