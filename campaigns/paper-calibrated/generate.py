#!/usr/bin/python3
"""Writes campaigns/paper-calibrated/*.toml from campaigns/paper/*.toml, and
campaigns/calibration/{targets,beverloo}-calibrated.toml from their -spec twins (issue 11), and
campaigns/calibration/flow-curve-<candidate>.toml from flow-curve-spec.toml, one per candidate of
the flow-curve recalibration (CANDIDATES below; issue 24).

usage: /usr/bin/python3 campaigns/paper-calibrated/generate.py

Each calibrated file is its spec-literal twin with the calibrated modelling choices (CALIBRATED
below; docs/calibration.md gives the argument for each) added to the base sections, and
"-calibrated" appended to the campaign name. Labels and campaign seeds are untouched, so every
realization has the same seed as its spec-literal twin: the two variants are paired samples.
A test (tests/config, ShippedCampaigns.CalibratedTwinsDifferOnlyInTheCalibratedChoices) checks
that the shipped files are what this script writes. Run it again after changing CALIBRATED.
"""
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER = os.path.join(HERE, "..", "paper")
CALIBRATION = os.path.join(HERE, "..", "calibration")

# section -> [(key, TOML value, why)]
CALIBRATED = {
    "walls": [
        ("spacing", "0.5", "smooth walls: wall disks overlapping by half a diameter"),
        ("edge_offset", "0.15",
         "the walls' rounded lower ends sit 0.15 wall diameters up the wall from the outlet corner"),
    ],
}

# Added to the paper studies only (issue 23; docs/clogging.md): with the calibrated walls, arches
# whose end disks sit in the groove between the edge disk and the next wall disk survive ten
# equal shakes; each further shake of a jam 1.5 times stronger (up to one large diameter) clears
# them. The calibration targets (D >= 4.1 cm) never jam and keep their physics.
PROTOCOL = {
    "protocol": [
        ("shake_growth", "1.5", "each further shake of one jam 1.5 times stronger (issue 23)"),
        ("shake_amplitude_max", "1.0", "up to one large-disk diameter"),
        ("max_shakes", "50", "a jam is given up only after 50 shakes"),
    ],
}


# The flow curve per candidate (issue 24; docs/calibration.md, "The flow curve per candidate"):
# candidate -> its modelling choices. "calibrated" is the shipped model; the others move the two
# levers the sensitivity study found (the walls' roughness, the wall end's height above the
# outlet corner) together: rougher walls slow the discharge at every outlet by about the same
# factor, a wider free gap speeds it up most at the smallest outlets, which flattens the curve.
CANDIDATES = {
    "calibrated": CALIBRATED,
    "rough-wide": {
        "walls": [
            ("spacing", "1.0", "rough walls: touching wall disks (the specification's default)"),
            ("edge_offset", "0.5",
             "the walls' rounded lower ends sit half a wall diameter up the wall"),
        ],
    },
    "medium-wide": {
        "walls": [
            ("spacing", "0.75", "walls of medium roughness: wall disks overlapping by a quarter"),
            ("edge_offset", "0.35",
             "the walls' rounded lower ends sit 0.35 wall diameters up the wall"),
        ],
    },
}


# The paper studies' model since issue 39 (docs/validation.md, "Medium-wide walls with mu_r
# 0.02" and "Smoother walls, spacing 0.6"): the free gap of the calibration's medium-wide walls,
# which the small outlets' empty times ask for, on walls a little smoother than theirs, and the
# rolling spring, which gives the clogging the published level and slope with that gap. The
# calibration targets' twins above keep issue 11's CALIBRATED walls: their stores and tables
# are that calibration's.
CLOGGING = {
    "walls": [
        ("spacing", "0.6", "nearly smooth walls: wall disks overlapping by 0.4 of a diameter"),
        ("edge_offset", "0.35",
         "the walls' rounded lower ends sit 0.35 wall diameters up the wall from the outlet corner"),
    ],
    "material": [
        ("mu_r", "0.02", "rolling resistance, about the contact's width over the radius of soft disks"),
        ("rolling_law", '"spring"', "a rolling spring capped at mu_r R* |F_n|, so that a clog holds"),
    ],
}


def mark(section):
    return "unjamming" if section == "protocol" else "calibrated"


def without_rolling_where_frictionless(text):
    """A point without static friction (mu = 0) or without the tangential spring (kt_over_kn =
    0) has nothing to roll against, and the engine refuses rolling resistance there: such points
    (the controls) set it back to none."""
    def fix(m):
        inner = m.group(2)
        if re.search(r"\b(mu|kt_over_kn) = 0\.0\b", inner):
            inner += ', mu_r = 0.0, rolling_law = "constant"'
        return m.group(1) + inner + m.group(3)
    return re.sub(r"(?m)^(material = \{ )(.*?)( \})", fix, text)


def calibrate(text, name, source="campaigns/paper", choices=CALIBRATED, suffix="-calibrated"):
    lines = text.split("\n")
    header = [
        "# CALIBRATED VARIANT (issue 11; written by campaigns/paper-calibrated/generate.py from",
        "# %s/%s, do not edit by hand): the spec-literal study plus the calibrated" % (source, name),
        "# modelling choices marked 'calibrated' below (docs/calibration.md). Same points, labels",
        "# and seeds as the spec-literal file.",
    ]
    if "material" in choices:
        header += ["# Walls and rolling resistance: issue 39's clogging model (docs/validation.md); points",
                   "# without static friction or tangential spring keep no rolling resistance."]
    if "protocol" in choices:
        header += ["# Unjamming marked 'unjamming': the growing shakes of issue 23 (docs/clogging.md)."]
    out = header + []
    seen = set()
    for line in lines:
        m = re.match(r"^\[([a-z]+)\]\s*$", line)
        out.append(line)
        if m and m.group(1) in choices:
            seen.add(m.group(1))
            for key, value, why in choices[m.group(1)]:
                out.append("%s = %s  # %s: %s" % (key, value, mark(m.group(1)), why))
    text = "\n".join(out)
    if "material" in choices:
        text = without_rolling_where_frictionless(text)
    # Sections the spec-literal file does not have: added before [campaign].
    extra = ""
    for section, items in choices.items():
        if section in seen:
            continue
        extra += "[%s]\n" % section
        for key, value, why in items:
            extra += "%s = %s  # %s: %s\n" % (key, value, mark(section), why)
        extra += "\n"
    if extra:
        text = text.replace("\n[campaign]\n", "\n" + extra + "[campaign]\n", 1)
    text = re.sub(r'(\nname = ")([^"]+)(")', lambda m: m.group(1) + m.group(2) + suffix +
                  m.group(3), text, count=1)
    return text


def main():
    for name in sorted(os.listdir(PAPER)):
        if not name.endswith(".toml"):
            continue
        with open(os.path.join(PAPER, name)) as fh:
            text = fh.read()
        with open(os.path.join(HERE, name), "w") as fh:
            fh.write(calibrate(text, name, choices={**CLOGGING, **PROTOCOL}))
        print("wrote campaigns/paper-calibrated/" + name)
    for stem in ("targets", "beverloo"):
        with open(os.path.join(CALIBRATION, stem + "-spec.toml")) as fh:
            text = fh.read()
        with open(os.path.join(CALIBRATION, stem + "-calibrated.toml"), "w") as fh:
            fh.write(calibrate(text, stem + "-spec.toml", "campaigns/calibration"))
        print("wrote campaigns/calibration/%s-calibrated.toml" % stem)
    # Per candidate: its flow curve, its empty times at the eight outlets, and (but for the
    # calibrated model, whose targets file is written above) its eleven large-outlet targets,
    # each paired with its -spec file.
    for stem, skip in (("flow-curve", ()), ("targets", ("calibrated",)), ("empty-times", ())):
        with open(os.path.join(CALIBRATION, stem + "-spec.toml")) as fh:
            text = fh.read()
        for candidate, choices in CANDIDATES.items():
            if candidate in skip:
                continue
            out = calibrate(text, stem + "-spec.toml", "campaigns/calibration", choices,
                            "-" + candidate)
            with open(os.path.join(CALIBRATION, "%s-%s.toml" % (stem, candidate)), "w") as fh:
                fh.write(out.replace("# CALIBRATED VARIANT (issue 11;",
                                     "# CANDIDATE '%s' (issue 24;" % candidate, 1))
            print("wrote campaigns/calibration/%s-%s.toml" % (stem, candidate))


if __name__ == "__main__":
    main()
