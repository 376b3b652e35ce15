"""Build src/uavcas/traffic/mavlink/data/arducopter_params.csv: ArduCopter's parameter list.

What it is: the names and default values of every parameter of an ArduCopter 4.6 firmware as a
freshly flashed flight controller reports them (PARAM_VALUE for each, 1095 of them), i.e. the
`00_default.param` "empty_4.6.x" template that ArduPilot's Methodic Configurator ships
(github.com/ArduPilot/MethodicConfigurator, PyPI `ardupilot-methodic-configurator` 5.0.1, GPL-3.0,
path ardupilot_methodic_configurator/vehicle_templates/ArduCopter/empty_4.6.x/00_default.param: a
parameter download from an ArduCopter 4.6 board with nothing configured). The ArduPilot
repository itself ships no full default dump (Tools/autotest/default_params/ and
Tools/Frame_params/ hold only overrides), and expanding every `@Param` of every library with its
group prefix is what ArduPilot's own param_parse.py does over the whole tree; the download is
that expansion as a real firmware performs it.

Types (MAV_PARAM_TYPE): a .param dump carries no types, so they are inferred, and this is an
approximation: a parameter whose ArduPilot documentation (the Configurator's copy of ArduPilot's
generated apm.pdef.xml for Copter 4.5, same wheel, diatone_taycan_mxc/4.5.x-params) lists
`Values` or a `Bitmask` is an AP_Int in ArduPilot: INT8 when its default and every listed value
fit in int8, else INT16, else INT32; every other parameter is REAL32 (AP_Float), which is also
what an integer-valued AP_Int16/32 without a value list (RC1_MIN, ...) becomes here.

Run (from the repository root, network access to PyPI only):
    pip download --no-deps ardupilot-methodic-configurator==5.0.1 -d /tmp/amc
    python scripts/make_arducopter_params.py /tmp/amc/ardupilot_methodic_configurator-5.0.1-py3-none-any.whl
"""

from __future__ import annotations

import csv
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

PREFIX = "ardupilot_methodic_configurator/vehicle_templates/ArduCopter/"
DUMP = PREFIX + "empty_4.6.x/00_default.param"
PDEF = PREFIX + "diatone_taycan_mxc/4.5.x-params/apm.pdef.xml"
OUT = Path(__file__).resolve().parents[1] / "src/uavcas/traffic/mavlink/data/arducopter_params.csv"


def _int_lists(pdef: bytes) -> dict[str, list[int]]:
    """Parameter name -> the integers its Values/Bitmask document (only parameters that have one)."""
    out: dict[str, list[int]] = {}
    for p in ET.fromstring(pdef).iter("param"):
        name = p.get("name", "").split(":")[-1]
        nums: list[int] = []
        found = False
        for v in p.iter("value"):  # <values><value code="N">...</value></values>
            found = True
            try:
                nums.append(int(float(v.get("code"))))
            except (TypeError, ValueError):
                pass
        for f in p.iter("field"):  # <field name="Bitmask">0:a,1:b,...</field>: the full mask's value
            if f.get("name") == "Bitmask" and f.text:
                found = True
                bits = [int(x.split(":")[0]) for x in f.text.split(",") if x.split(":")[0].strip().isdigit()]
                nums.append((1 << (max(bits) + 1)) - 1 if bits else 0)
        if found:
            out[name] = nums
    return out


def _type(name: str, value: float, ints: dict[str, list[int]]) -> str:
    if name not in ints or value != int(value):
        return "REAL32"
    span = [int(value), *ints[name]]
    if all(-128 <= v <= 127 for v in span):
        return "INT8"
    if all(-32768 <= v <= 32767 for v in span):
        return "INT16"
    return "INT32"


def main(wheel: str) -> int:
    with zipfile.ZipFile(wheel) as z:
        dump, pdef = z.read(DUMP).decode(), z.read(PDEF)
    ints = _int_lists(pdef)
    rows = []
    for line in dump.splitlines():
        line = line.split("#")[0].strip()
        if not line:
            continue
        name, value = line.replace("\t", ",").split(",")[:2]
        rows.append((name.strip(), float(value), _type(name.strip(), float(value), ints)))
    OUT.parent.mkdir(parents=True, exist_ok=True)
    with OUT.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["name", "default", "type"])
        for name, value, typ in rows:
            w.writerow([name, repr(value) if value != int(value) else str(int(value)), typ])
    print(f"{len(rows)} parameters -> {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
