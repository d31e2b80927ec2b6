"""``symkin rate --datasheet SPEC.yaml`` (issue 64): a maker's published figures beside symkin's, and a spec file
from a stranger refused with located reasons (it is data: read as a model file is)."""

from __future__ import annotations

import json

import pytest

from conftest import GENERATED_DIR, MODELS_DIR
from symkin.cli import main
from symkin.rating.maker_figures import read_maker_sheet

PHANTOM_SPEC = MODELS_DIR / "datasheets" / "phantom_premium.yaml"


def test_the_phantoms_figures_stand_beside_its_makers(tmp_path, capsys):
    """The shipped spec (SensAble's figures): each beside symkin's at the nominal (home) pose, with the ratio, in
    summary.txt and datasheet.json; the force along x is the maker's 8.5 N within its printed digits."""
    out = tmp_path / "rate"
    assert main(["rate", str(GENERATED_DIR / "phantom_premium"), "--encoder", "4096", "-n", "64", "--no-figure",
                 "--datasheet", str(PHANTOM_SPEC), "-o", str(out)]) == 0
    record = json.loads((out / "datasheet.json").read_text())
    figures = {f["measure"]: f for f in record["maker"]["figures"]}
    assert list(figures) == [f.measure for f in read_maker_sheet(PHANTOM_SPEC).figures]
    for name, figure in figures.items():
        assert figure["symkin"] == record["measures"][name]["home"]
        assert figure["ratio"] == figure["symkin"] / figure["maker"]          # the same division, printed exactly
    assert figures["force_x"]["maker"] == 8.5
    assert abs(figures["force_x"]["ratio"] - 1) < 0.05 / 8.5
    # the ratios docs/analysis.md quotes and explains, to their printed digits
    quoted = {"force_x": "0.998", "continuous_force_x": "1.37", "resolution_x": "0.78", "backdrive_friction_x": "1.47",
              "apparent_mass_x": "0.49", "quantization_stiffness_x": "1.44"}
    for name, text in quoted.items():
        decimals = len(text.split(".")[1])
        assert round(figures[name]["ratio"], decimals) == float(text), (name, figures[name]["ratio"])
    masses = [round(1e3 * record["measures"][f"apparent_mass_{axis}"]["home"]) for axis in "xyz"]
    assert masses == [37, 81, 55]                                   # g, as docs/analysis.md quotes them
    walls = [round(1e-3 * record["measures"][f"quantization_stiffness_{axis}"]["home"], 1) for axis in "xyz"]
    assert walls == [5.1, 3.8, 3.2]                                 # N/mm, as docs/analysis.md quotes them
    assert round(record["measures"]["passive_stiffness_x"]["home"]) == 35       # N/m
    box = record["maker"]["workspace_box"]                          # SensAble's box does not fit (docs/analysis.md)
    assert box["maker_m"] == [0.191, 0.381, 0.267]
    assert box["fits"] is False
    assert round(box["volume_ratio"], 2) == 0.58
    assert "fits inside the usable workspace: no" in (out / "summary.txt").read_text()
    shapes = record["workspace_shapes"]                             # mm, as docs/analysis.md quotes them
    assert [round(1e3 * size) for size in shapes["box"]["size_m"]] == [109, 473, 218]
    cylinder = shapes["cylinder"]
    assert (round(2e3 * cylinder["radius_m"]), round(1e3 * (cylinder["top_m"] - cylinder["bottom_m"]))) == (167, 218)
    summary = (out / "summary.txt").read_text()
    assert "beside the maker's figures (PHANToM Premium 1.5 (SensAble Technologies);" in summary
    assert "force_x at home: symkin 8.479 N, maker 8.5 N, ratio 0.998" in summary


def test_a_figure_of_a_measure_not_rated_says_why(tmp_path):
    """Without --encoder the resolution is not rated: its figure stands beside the reason, not a number."""
    out = tmp_path / "rate"
    assert main(["rate", str(GENERATED_DIR / "phantom_premium"), "-n", "64", "--no-figure",
                 "--datasheet", str(PHANTOM_SPEC), "-o", str(out)]) == 0
    figure = next(f for f in json.loads((out / "datasheet.json").read_text())["maker"]["figures"]
                  if f["measure"] == "resolution_x")
    assert figure["symkin"] is None
    assert figure["ratio"] is None
    assert "--encoder" in figure["not_rated"]


HOSTILE = {
    "a list": ("- 1\n- 2\n", "a spec file is a mapping"),
    "a python tag": ("device: !!python/object/apply:os.system ['true']\nsource: s\nfigures: {force_x: {value: 1, "
                     "unit: N}}\n", "tag"),
    "no figures": ("device: d\nsource: s\n", "'figures' must be a non-empty mapping"),
    "an unknown key": ("device: d\nsource: s\nrun: now\nfigures: {force_x: {value: 1, unit: N}}\n",
                       "unknown key 'run'"),
    "a text value": ("device: d\nsource: s\nfigures: {force_x: {value: lots, unit: N}}\n",
                     "the value must be a finite number"),
    "a boolean value": ("device: d\nsource: s\nfigures: {force_x: {value: true, unit: N}}\n",
                        "the value must be a finite number"),
    "an infinite value": ("device: d\nsource: s\nfigures: {force_x: {value: .inf, unit: N}}\n",
                          "the value must be a finite number"),
    "a bad place": ("device: d\nsource: s\nfigures: {force_x: {value: 1, unit: N, at: everywhere}}\n",
                    "'at' must be one of home, worst"),
    "a flat workspace box": ("device: d\nsource: s\nfigures: {force_x: {value: 1, unit: N}}\n"
                             "workspace: {box: [0.1, 0.2], unit: m}\n", "the box must be three positive sizes"),
    "a workspace box in mm": ("device: d\nsource: s\nfigures: {force_x: {value: 1, unit: N}}\n"
                              "workspace: {box: [191, 381, 267], unit: mm}\n", "the box's unit must be m"),
    "a workspace list": ("device: d\nsource: s\nfigures: {force_x: {value: 1, unit: N}}\nworkspace: [1, 2]\n",
                         "the workspace is a mapping"),
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_a_bad_spec_file_is_refused_with_its_place_and_nothing_is_written(name, tmp_path, capsys):
    text, said = HOSTILE[name]
    spec = tmp_path / "spec.yaml"
    spec.write_text(text)
    out = tmp_path / "rate"
    assert main(["rate", str(GENERATED_DIR / "phantom_premium"), "-n", "16", "--no-figure", "--datasheet", str(spec),
                 "-o", str(out)]) == 2
    error = capsys.readouterr().err
    assert said in error
    assert str(spec) in error
    assert "fix:" in error
    assert not out.exists()


@pytest.mark.parametrize("figure, said", [
    ("force_w: {value: 1, unit: N}", "figures.force_w: no such measure of this device; use one of"),
    ("resolution_x: {value: 0.03, unit: mm}", "'mm' where the datasheet gives resolution_x in 'm'"),
])
def test_a_figure_the_datasheet_cannot_set_beside_its_own_is_refused(figure, said, tmp_path, capsys):
    spec = tmp_path / "spec.yaml"
    spec.write_text(f"device: d\nsource: s\nfigures: {{{figure}}}\n")
    out = tmp_path / "rate"
    with pytest.raises(SystemExit) as exited:                  # argparse's exit on bad input, as the command's
        main(["rate", str(GENERATED_DIR / "phantom_premium"), "--encoder", "4096", "-n", "16", "--no-figure",
              "--datasheet", str(spec), "-o", str(out)])
    assert exited.value.code == 2
    assert said in capsys.readouterr().err
    assert not out.exists()


def test_a_makers_text_cannot_forge_lines_of_the_summary(tmp_path):
    """A quote with a line break and control characters is one printable line in summary.txt."""
    spec = tmp_path / "spec.yaml"
    spec.write_text('device: "d\\nforce_x at home: symkin 1000 N"\nsource: "s\\u001b[2J"\n'
                    'figures: {force_x: {value: 8.5, unit: N, quote: "a\\nforged line"}}\n')
    out = tmp_path / "rate"
    assert main(["rate", str(GENERATED_DIR / "phantom_premium"), "-n", "16", "--no-figure", "--datasheet", str(spec),
                 "-o", str(out)]) == 0
    summary = (out / "summary.txt").read_text()
    assert "\nforged line" not in summary
    assert "\x1b" not in summary
    assert "\nforce_x at home: symkin 1000 N" not in summary
