"""An attack family is added by one row of `uavcas.vocabulary.ROWS` and one module in
`uavcas.attacks` (issue 40).

A copy of the package gets a throwaway family, `synflood`: a SYN flood of its own (class
`SYNFlood`, effect `synflood` ranked between replay and flood, label source `synflood-packets`)
that reuses the flood's tool, executor and truth rule. In a fresh interpreter that imports only the
copy, the vocabulary derives its words from the row (the words before it keep their codes and
order), the codec parses its token and `uavcas plan` plans it, the CLI names it among the families
it offers, and a run directory whose flood is the new family's (the labels' synthetic run, its
attack renamed) is extracted into a dataset whose packets carry its effect, whose flows carry its
class and label source, and whose card and `uavcas info` list it. The root test
(test_family_dropin_root.py) runs it on real stacks.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from helpers.family_dropin import CONFIG, copy_with_throwaway
from helpers.plugin import run_on


def _as_synflood(run_dir: Path) -> Path:
    """The synthetic run with its DoS attack made a synflood attack: plan, scenario, log, run.json."""

    def swap(x):
        if isinstance(x, dict):
            return {k: "synflood" if (k == "family" and v == "dos") else swap(v) for k, v in x.items()}
        if isinstance(x, list):
            return [swap(i) for i in x]
        return x.replace("dos-0", "synflood-0") if isinstance(x, str) else x

    old, new = "blackhole+dos=1000+replay=50,200,10,5,inc", "blackhole+replay=50,200,10,5,inc+synflood=1000"
    plan = swap(json.loads((run_dir / "plan.json").read_text()))
    assert plan["config"].startswith(old)
    plan["config"] = plan["config"].replace(old, new)
    plan["scenario"]["attacks"].sort(key=lambda a: a["family"])  # canonical order
    (run_dir / "plan.json").write_text(json.dumps(plan))
    lines = [json.dumps(swap(json.loads(line))) for line in (run_dir / "attacks.jsonl").read_text().splitlines()]
    (run_dir / "attacks.jsonl").write_text("\n".join(lines) + "\n")
    info = json.loads((run_dir / "run.json").read_text())
    info["config"] = info["config"].replace(old, new)
    (run_dir / "run.json").write_text(json.dumps(info))
    return run_dir


PROBE = """
import json
from uavcas import vocabulary as v
from uavcas.attacks import family
from uavcas.labels.label import SOURCES
from uavcas.scenario import parse
f = family("synflood")
sc = parse("synflood=500+dos=1000-4-1-image-logdist-adaptive-grid-30-95")
print(json.dumps(dict(families=v.FAMILIES, effects=v.EFFECTS, precedence=v.EFFECT_PRECEDENCE,
                      attack_effects=v.ATTACK_EFFECTS, sources=SOURCES, classes=v.CLASSES,
                      label_columns=v.LABEL_COLUMNS, words=[f.effect, f.label_source, f.class_name],
                      tokens=[a.token() for a in sc.attacks], klass=v.class_name(sc.families))))
"""


@pytest.mark.slow  # 25 s on 2 cores
def test_one_row_and_one_module_add_a_family_through_plan_truth_labels_card_and_cli(synth_run_dir, tmp_path):
    from uavcas import vocabulary as v

    pkg = copy_with_throwaway(tmp_path)
    probe = run_on(pkg, "-c", PROBE)
    assert probe.returncode == 0, probe.stderr
    got = json.loads(probe.stdout)
    # the words derive from the row; those before it keep their codes and their order
    assert got["families"] == sorted([*v.FAMILIES, "synflood"])
    assert got["effects"] == [*v.EFFECTS, "synflood"]  # appended: stored effect codes keep their meaning
    assert got["precedence"] == ["replay", "synflood", *v.EFFECT_PRECEDENCE[1:]]
    assert got["attack_effects"] == [*v.ATTACK_EFFECTS, "synflood"]
    assert got["sources"][-2:] == ["synflood-packets", "ip-membership"]
    assert "label_synflood" in got["label_columns"] and "SYNFlood" in got["classes"]
    assert got["words"] == ["synflood", "synflood-packets", "SYNFlood"]
    assert got["tokens"] == ["dos=1000", "synflood=500"] and got["klass"] == "DoS+SYNFlood"

    # plan: the codec parses its token, the planner schedules it
    out = tmp_path / "plan.json"
    planned = run_on(pkg, "-m", "uavcas", "plan", CONFIG, "--windows", "3", "--out", str(out))
    assert planned.returncode == 0, planned.stderr
    assert "attack synflood-0" in planned.stdout
    (att,) = json.loads(out.read_text())["attacks"]
    assert att["family"] == "synflood" and att["spec"] == {"family": "synflood", "interval_us": 1000}
    # the CLI offers it among the families, and refuses a family no row holds in one line
    refused = run_on(pkg, "-m", "uavcas", "plan", "teleport-4-1-image-logdist-adaptive-grid-30-95")
    assert refused.returncode != 0 and "synflood=<us>" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1

    # truth and labels: its packets carry its effect, its flows its class and label source
    run_dir = _as_synflood(shutil.copytree(synth_run_dir, tmp_path / "run"))
    ds = tmp_path / "ds"
    made = run_on(pkg, "-m", "uavcas", "extract", str(run_dir), "--out", str(ds))
    assert made.returncode == 0, made.stderr
    flows = pq.read_table(ds / "flows.parquet").to_pandas()
    syn = flows[flows["label_synflood"]]
    assert len(syn) > 0 and set(syn["label"]) == {"SYNFlood"} and set(syn["label_source"]) == {"synflood-packets"}
    assert (syn["attack_packets_synflood"] > 0).all() and not flows["label_dos"].any()
    assert all("synflood" in set(seq) for seq in syn["seq_effect"])
    assert {"Blackhole", "Replay", "Benign"} <= set(flows["label"])  # the run's other families as before
    card = json.loads((ds / "dataset.json").read_text())
    assert card["class_counts"]["SYNFlood"] == len(syn)
    assert any("synflood:" in rule for rule in card["label_rules"])
    listed = run_on(pkg, "-m", "uavcas", "info", str(ds))
    assert listed.returncode == 0, listed.stderr
    assert "SYNFlood" in listed.stdout
    columns = run_on(pkg, "-m", "uavcas", "info", str(ds), "--columns")
    assert columns.returncode == 0, columns.stderr
    row = next(line for line in columns.stdout.splitlines() if line.startswith("label_synflood\t"))
    assert "SYNFlood" in row
