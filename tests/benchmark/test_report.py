"""Benchmark records files and the Markdown tables: round trips, corruption, markers, determinism."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from catgrasp_drake.benchmark.report import (
    MARKERS,
    RECORDS_FORMAT,
    benchmark_tables,
    check_markdown,
    committed_models,
    load_benchmark_records,
    markdown_tables,
    merged_records,
    report,
    summary_table,
    update_markdown,
    write_benchmark_records,
)
from catgrasp_drake.errors import InputError, ModelFileError

#: method -> (grasp, functional) success probability of the synthetic trials
RATES = {"latent": (0.85, 0.65), "nearest": (0.6, 0.3), "rigid": (0.5, 0.2), "true_object": (0.95, 0.85)}


def synthetic_records(seed: int = 0) -> list[dict]:
    """Seeded records shaped like the runner's: two test categories x 4 instances x 2 views x 3 trials, a small
    ycb split, and the latent method once more under ``friction_0.5`` (its outcomes perturbed)."""
    rng = np.random.default_rng(seed)
    out = []
    cells = [("test", "drill", [f"drill_t{i:02d}" for i in range(4)], 3, ("single", "full")),
             ("test", "spray_bottle", [f"spray_bottle_t{i:02d}" for i in range(4)], 3, ("single", "full")),
             ("ycb", "drill", ["ycb_035", "ycb_036"], 2, ("single",))]
    for split, category, instances, trials, views in cells:
        for instance in instances:
            bias = rng.normal(0.0, 0.1)
            for view in views:
                for trial in range(trials):
                    u, v = rng.random(2)  # shared by the methods: paired trials are correlated
                    for method, (pg, pf) in RATES.items():
                        if split == "ycb" and method in ("nearest", "true_object"):
                            continue
                        settings = ("default", "friction_0.5") if method == "latent" and split == "test" \
                            else ("default",)
                        for physics in settings:
                            jitter = rng.normal(0.0, 0.2) if physics != "default" else 0.0
                            grasp = bool(u < pg + bias + jitter)
                            functional = bool(grasp and v < pf / pg)
                            reason = None if functional else (
                                "wrong_part" if grasp else str(rng.choice(["slipped", "collision"])))
                            out.append({
                                "split": split, "category": category, "instance": instance, "trial": trial,
                                "view": view, "method": method, "physics": physics, "grasp": grasp,
                                "functional": functional, "reason": reason, "detail": "",
                                "confidence": float(rng.random()), "plan_status": "ok",
                                "placement": {"yaw_deg": float(rng.uniform(-180, 180)), "xyz": [0.0, 0.0, 0.0]},
                                "camera": {}, "code_version": "synthetic", "seed": seed,
                                "timings": {"perceive": float(rng.uniform(0.1, 0.3)),
                                            "estimate": float(rng.uniform(0.05, 2.0)),
                                            "plan": float(rng.uniform(0.02, 0.1)),
                                            "execute": float(rng.uniform(3, 6)),
                                            "total": float(rng.uniform(4, 9)),
                                            "simulated_s": float(rng.uniform(5, 8))}})
    return out


@pytest.fixture(scope="module")
def records():
    return synthetic_records()


# ----------------------------------------------------------------------------- records files
def test_records_round_trip(tmp_path, records):
    path = tmp_path / "results" / "run.jsonl"
    write_benchmark_records(path, records)
    lines = path.read_text().splitlines()
    header = json.loads(lines[0])
    assert header["format"] == RECORDS_FORMAT and header["format_version"] == 1
    assert header["records"] == len(records) == len(lines) - 1
    assert list(json.loads(lines[1])) == sorted(json.loads(lines[1]))  # keys sorted
    assert load_benchmark_records(path) == records
    # several files, or a folder of them, are concatenated
    write_benchmark_records(tmp_path / "results" / "more.jsonl", records[:5])
    assert load_benchmark_records([path, tmp_path / "results" / "more.jsonl"]) == records + records[:5]
    assert len(load_benchmark_records(tmp_path / "results")) == len(records) + 5
    with pytest.raises(InputError, match="missing fields"):
        write_benchmark_records(tmp_path / "bad.jsonl", [{"split": "test"}])


def _assert_one_line_naming(err, path):
    msg = str(err.value)
    assert str(path) in msg and "\n" not in msg


def test_a_merge_replaces_the_rerun_trials_in_place_and_keeps_the_others(records):
    old = [r for r in records if r["split"] == "test"]
    rerun = [dict(r, functional=not r["functional"], code_version="rerun") for r in old
             if r["category"] == "spray_bottle" and r["method"] == "latent"]
    extra = [dict(r, trial=7, code_version="rerun") for r in rerun[:2]]  # trials the file did not hold
    merged = merged_records(old, rerun + extra)
    assert len(merged) == len(old) + 2 and merged[-2:] == extra
    for before, after in zip(old, merged):  # same order, the re-run trials replaced where they were
        replaced = before["category"] == "spray_bottle" and before["method"] == "latent"
        assert after["code_version"] == ("rerun" if replaced else "synthetic")
        assert after["functional"] == (not before["functional"] if replaced else before["functional"])
    assert merged_records([], rerun) == rerun
    with pytest.raises(InputError, match="same trial twice"):
        merged_records(old, rerun + rerun[:1])


def test_corrupted_records_file_names_the_file(tmp_path, records):
    path = tmp_path / "run.jsonl"
    write_benchmark_records(path, records[:10])
    lines = path.read_text().splitlines(keepends=True)
    line = lines[3]  # the third record: flip its grasp outcome
    edited = line.replace('"grasp": true', '"grasp": false') if '"grasp": true' in line else \
        line.replace('"grasp": false', '"grasp": true')
    assert edited != line
    path.write_text("".join(lines[:3] + [edited] + lines[4:]))
    with pytest.raises(ModelFileError, match="checksum mismatch") as err:
        load_benchmark_records(path)
    _assert_one_line_naming(err, path)


@pytest.mark.parametrize("damage, message", [
    (lambda lines: lines[:-1], "checksum mismatch"),                     # a record line removed
    (lambda lines: lines[1:], "no header"),                              # header removed
    (lambda lines: [lines[0].replace("catgrasp.benchmark_records", "catgrasp.eval_records")] + lines[1:],
     "expected 'catgrasp.benchmark_records'"),
    (lambda lines: [lines[0].replace('"format_version": 1', '"format_version": 2')] + lines[1:], "version 2"),
    (lambda lines: [], "no header"),
])
def test_damaged_records_files(tmp_path, records, damage, message):
    path = tmp_path / "run.jsonl"
    write_benchmark_records(path, records[:4])
    path.write_text("".join(damage(path.read_text().splitlines(keepends=True))))
    with pytest.raises(ModelFileError, match=message) as err:
        load_benchmark_records(path)
    _assert_one_line_naming(err, path)
    with pytest.raises(ModelFileError) as err:
        load_benchmark_records(tmp_path / "absent.jsonl")
    _assert_one_line_naming(err, tmp_path / "absent.jsonl")


# ----------------------------------------------------------------------------- tables
def test_tables_are_deterministic(records):
    first = benchmark_tables(records)
    assert benchmark_tables(records) == first
    shuffled = [records[i] for i in np.random.default_rng(1).permutation(len(records))]
    assert benchmark_tables(shuffled) == first
    assert summary_table(shuffled) == summary_table(records)
    assert markdown_tables(records) == {"summary": summary_table(records), "full": first}
    assert set(markdown_tables(records)) == set(MARKERS)


def test_full_tables_structure(records):
    text = benchmark_tables(records)
    test_part, ycb_part = text.split("### Split `test`")[1].split("### Split `ycb`")
    drill_single = test_part.split("**drill, single view**")[1].split("**")[0]
    rows = [line.split(" | ")[0].lstrip("| ") for line in drill_single.strip().splitlines()[2:]]
    assert rows == ["latent", "nearest", "rigid", "true-object planner (ablation)"]
    assert "**drill + spray bottle, single view** (bootstrap stratified by category)" in test_part
    assert "drill + spray bottle" not in ycb_part.split("### Physics")[0]  # ycb has no spray bottles
    assert "Latent minus baseline" in test_part and "| drill + spray bottle | single | rigid |" in test_part
    # a view whose baselines ran on drills only: a drill row, no pooled "drill + spray bottle" row
    drill_full = [r for r in records if not (r["view"] == "full" and r["category"] == "spray_bottle"
                                             and r["method"] != "latent")]
    text_drill_full = benchmark_tables(drill_full).split("### Split `test`")[1].split("### Split `ycb`")[0]
    assert "| drill | full | rigid |" in text_drill_full
    assert "| drill + spray bottle | full | rigid |" not in text_drill_full
    assert "| drill + spray bottle | full | rigid |" in test_part
    assert "### Physics sensitivity" in text and "`friction_0.5`" in text
    assert "### Failure reasons" in text and "`wrong_part`" in text
    assert "### Cost" in text and f"| all | all | {len(records)} |" in text
    default_only = [r for r in records if r["physics"] == "default"]
    assert "### Physics sensitivity" not in benchmark_tables(default_only)
    assert benchmark_tables([]) == "No benchmark records."


def test_known_cells():
    def rec(instance, trial, method, ok, category="drill"):
        return {"split": "test", "category": category, "instance": instance, "trial": trial, "view": "single",
                "method": method, "physics": "default", "grasp": ok, "functional": ok, "reason": None,
                "timings": {"total": 2.0}}

    rs = [rec(f"drill_t{i:02d}", t, "latent", True) for i in range(10) for t in range(3)]
    rs += [rec(f"drill_t{i:02d}", t, "rigid", i < 2) for i in range(10) for t in range(3)]
    rs += [rec(f"drill_t{i:02d}", t, "paper", i < 5) for i in range(10) for t in range(3)]
    text = benchmark_tables(rs)
    assert "| latent | 30 | 30/30 (100 %) [100–100 %] | 30/30 (100 %) [100–100 %] | 10 | 2.0 s |" in text
    table = text.split("**drill, single view**")[1].split("**")[0]
    assert [line.split(" | ")[0] for line in table.strip().splitlines()[2:]] == ["| latent", "| paper", "| rigid"]
    # latent minus rigid: +80 pp, the interval excludes 0
    rigid = [line for line in text.splitlines() if line.startswith("| drill | single | rigid |")][0]
    assert "| +80 pp [" in rigid and "| yes |" in rigid
    summary = summary_table(rs)
    assert "| `test` | drill | 30 | 30/30 (100 %) [100–100 %] | 30/30 (100 %) [100–100 %] | paper | 15/30 (50 %)" \
        in summary


# ----------------------------------------------------------------------------- Markdown files
DOC = """# Results

Intro text.

<!-- benchmark:summary -->
old summary
<!-- /benchmark:summary -->

Between.

<!-- benchmark:full -->
<!-- /benchmark:full -->

Tail.
"""


def test_update_markdown_round_trip(tmp_path, records):
    path = tmp_path / "doc.md"
    path.write_text(DOC)
    tables = markdown_tables(records)
    new = update_markdown(path, tables)
    assert path.read_text() == new
    assert new.startswith("# Results\n\nIntro text.\n\n<!-- benchmark:summary -->\n| split |")
    assert "\nBetween.\n" in new and new.endswith("<!-- /benchmark:full -->\n\nTail.\n")
    assert new.split("<!-- benchmark:full -->\n")[1].split("<!-- /benchmark:full -->")[0] == tables["full"]
    assert check_markdown(path, records) == []
    assert update_markdown(path, tables) == new  # idempotent
    # only the named markers change
    assert update_markdown(path, {"summary": "x"}).split("<!-- benchmark:full -->")[1] == \
        new.split("<!-- benchmark:full -->")[1]
    assert check_markdown(path, records) == ["summary"]
    path.write_text(path.read_text().replace("x\n<!-- /benchmark:summary", tables["summary"] +
                                             "<!-- /benchmark:summary"))
    assert check_markdown(path, records) == []
    edited = path.read_text().replace("| latent |", "| latent (edited) |", 1)
    path.write_text(edited)
    assert check_markdown(path, records) == ["full"]


@pytest.mark.parametrize("text, message", [
    ("# nothing here\n", "no <!-- benchmark:full --> marker"),
    ("<!-- benchmark:full -->\nno end\n", "unbalanced"),
    ("<!-- /benchmark:full -->\n<!-- benchmark:full -->\n", "unbalanced"),
    ("<!-- benchmark:full -->\n<!-- benchmark:full -->\n<!-- /benchmark:full -->\n", "unbalanced"),
])
def test_update_markdown_refuses_missing_or_unbalanced_markers(tmp_path, text, message):
    path = tmp_path / "doc.md"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as err:
        update_markdown(path, {"full": "table"})
    _assert_one_line_naming(err, path)
    assert path.read_text() == text  # untouched


def test_report_fills_every_file_and_check_agrees(tmp_path, records):
    results = tmp_path / "results"
    write_benchmark_records(results / "test.jsonl", [r for r in records if r["split"] == "test"])
    write_benchmark_records(results / "ycb.jsonl", [r for r in records if r["split"] == "ycb"])
    readme, doc = tmp_path / "README.md", tmp_path / "benchmark.md"
    readme_text = "# Project\n\n<!-- benchmark:summary -->\n<!-- /benchmark:summary -->\n"
    readme.write_text(readme_text)
    doc.write_text(DOC)
    dry = report(sorted(results.glob("*.jsonl")), [readme, doc], write=False)
    assert readme.read_text() == readme_text and doc.read_text() == DOC  # write=False: nothing written
    out = report(results, [readme, doc])
    assert out == dry
    assert out == {str(readme): readme.read_text(), str(doc): doc.read_text()}
    loaded = load_benchmark_records(results)
    assert check_markdown(readme, loaded) == [] and check_markdown(doc, loaded) == []
    assert check_markdown(readme, loaded[:-1]) == ["summary"]
    assert report(results, [readme, doc]) == out  # same records -> same text
    plain = tmp_path / "plain.md"
    plain.write_text("# no markers\n")
    with pytest.raises(InputError, match="no benchmark markers"):
        report(results, [readme, plain])


def test_imports_without_drake():
    code = ("import sys; import catgrasp_drake.benchmark.report, catgrasp_drake.benchmark.stats; "
            "sys.exit(1 if any(m.split('.')[0] == 'pydrake' for m in sys.modules) else 0)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_the_same_trial_twice_is_refused_but_another_seed_is_another_trial(records):
    with pytest.raises(InputError, match="same trial twice"):
        benchmark_tables(records + records[:1])
    with pytest.raises(InputError, match="same trial twice"):
        summary_table(records + records[:1])
    reseeded = [r | {"seed": 7} for r in records]
    text = benchmark_tables(records + reseeded)
    assert f"| all | all | {2 * len(records)} |" in text
    assert "| drill | single | rigid | 24 |" in text  # paired within each seed: 12 trials x 2 seeds


def test_one_instance_gets_no_interval():
    from catgrasp_drake.benchmark.report import _rate

    assert _rate(["ycb_035"] * 6, [1, 0, 0, 0, 0, 0]) == "1/6 (17 %) [1 instance]"
    assert _rate(["a", "a", "b", "b"], [1, 1, 0, 0]).startswith("2/4 (50 %) [0–100 %]")
    # pooled over categories: one instance per stratum is still one instance to resample in each
    assert _rate(["d", "s"], [1, 0], strata=["drill", "spray"]).endswith("[1 instance]")


def test_the_more_views_section_pairs_each_trial_with_its_single_view():
    def rec(instance, trial, view, ok, views_used=1):
        return {"split": "test", "category": "mug", "instance": instance, "trial": trial, "view": view,
                "method": "latent", "physics": "default", "grasp": ok, "functional": ok, "reason": None,
                "seed": 0, "views_used": views_used, "timings": {"total": 2.0}}

    # 10 mugs x 3 trials; the single view functional on mugs 0-3; the active view takes a second look on
    # mugs 4-9's trials 0-1 (a third on mug 9's) and puts those right (12 more), keeps the rest as they were
    rs = [rec(f"mug_t{i:02d}", t, "single", i < 4) for i in range(10) for t in range(3)]
    rs += [rec(f"mug_t{i:02d}", t, "active", i < 4 or t < 2, (3 if i == 9 else 2) if i >= 4 and t < 2 else 1)
           for i in range(10) for t in range(3)]
    text = benchmark_tables(rs)
    assert "### More views" in text
    row = [line for line in text.splitlines() if line.startswith("| `test` | mug | latent | active |")][0]
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[4:8] == ["30", "18 / 10 / 2", "12/30", "24/30"]
    assert cells[8].startswith("+40 pp [")
    # no records of further views: no section
    assert "### More views" not in benchmark_tables([r for r in rs if r["view"] == "single"])


def test_a_tuning_split_is_in_the_full_tables_but_never_in_the_summary():
    def rec(split, instance, trial, ok):
        return {"split": split, "category": "drill", "instance": instance, "trial": trial, "view": "single",
                "method": "latent", "physics": "default", "grasp": ok, "functional": ok, "reason": None,
                "timings": {"total": 2.0}}

    rs = [rec("test", f"drill_t{i:02d}", 0, True) for i in range(4)]
    rs += [rec("stress", f"drill_{i:02d}_deep", 0, i < 1) for i in range(4)]
    rs += [rec("val", f"drill_{i:02d}", 0, i < 2) for i in range(4)]
    summary = summary_table(rs)
    assert "`test`" in summary and "`stress`" not in summary and "`val`" not in summary
    assert "| `stress` | drill | 4 |" in summary_table(rs, tuning=True)  # the CLI's summary of a tuning run
    assert "| `val` | drill | 4 |" in summary_table(rs, tuning=True)
    full = benchmark_tables(rs)
    assert "Split `stress`: the committed instances stretched to real proportions (a TUNING set" in full
    assert "Split `val`: generated instances of the validation seed: novel draws (a TUNING set" in full
    assert "1/4 (25 %)" in full and "2/4 (50 %)" in full


def test_fresh_seeds_pool_as_distinct_objects_and_pair_within_their_seed():
    """Two fresh data-set seeds both name their instances ``mug_00``..: the tables count them as different objects
    (``mug_00@31`` is not ``mug_00@32``), pair methods only within a seed, and a records merge keeps both."""
    def rec(data_seed, instance, trial, method, ok):
        return {"split": "fresh", "data_seed": data_seed, "category": "mug", "instance": instance, "trial": trial,
                "view": "single", "method": method, "physics": "default", "seed": 0, "grasp": ok, "functional": ok,
                "reason": None, "timings": {"total": 2.0}}

    # seed 31: latent grasps every mug, rigid none; seed 32: rigid only ran on mug_00..01, latent fails there
    rs = [rec(31, f"mug_{i:02d}", t, m, m == "latent") for i in range(3) for t in range(2) for m in ("latent", "rigid")]
    rs += [rec(32, f"mug_{i:02d}", t, "latent", False) for i in range(3) for t in range(2)]
    rs += [rec(32, f"mug_{i:02d}", t, "rigid", True) for i in range(2) for t in range(2)]
    text = benchmark_tables(rs)
    assert "never seen (data-set seeds 31, 32)" in text
    assert "| latent | 12 | 6/12 (50 %) [" in text and "| 6 | 2.0 s |" in text  # 6 objects, not 3
    assert "| rigid | 10 | 4/10 (40 %) [" in text
    row = [line for line in text.splitlines() if line.startswith("| mug | single | rigid |")][0]
    # 10 pairs (seed 31: 6, seed 32: 4): latent 6/10, rigid 4/10; a cross-seed pairing would give other counts
    assert "| 10 | 6/10 (60 %) | 4/10 (40 %) | +20 pp [" in row
    summary = summary_table(rs)
    assert "| `fresh` | mug | 12 | 6/12 (50 %) [" in summary and "| rigid (10 trials) | 4/10 (40 %)" in summary
    merged = merged_records([r for r in rs if r["data_seed"] == 31], [r for r in rs if r["data_seed"] == 32])
    assert len(merged) == len(rs)
    with pytest.raises(InputError, match="same trial twice"):
        benchmark_tables(rs + rs[-1:])


def test_report_print_shows_one_files_tables_and_writes_nothing(tmp_path, records, capsys):
    """``catgrasp report --records FILE --print``: every table of those records on stdout, no Markdown touched."""
    from catgrasp_drake.cli import main

    path = tmp_path / "experiment.jsonl"
    write_benchmark_records(path, records)
    readme = tmp_path / "README.md"
    readme.write_text("# Project\n\n<!-- benchmark:summary -->\n<!-- /benchmark:summary -->\n")
    before = readme.read_text()
    assert main(["report", "--records", str(path), "--print", "--markdown", str(readme)]) == 0
    # marked against the committed models (these synthetic trials carry none)
    assert capsys.readouterr().out == benchmark_tables(records, committed=committed_models())
    assert readme.read_text() == before


def test_rows_run_with_another_model_than_the_committed_one_are_marked():
    """A row of the summary (and a table of the full report) whose trials carry another ``model_sha256`` than the
    committed model of their category says so; rows of the committed model, and categories without a committed
    model (an example folder's), are not marked."""
    def rec(category, instance, method, sha):
        return {"split": "test", "category": category, "instance": instance, "trial": 0, "view": "single",
                "method": method, "physics": "default", "seed": 0, "grasp": True, "functional": True,
                "reason": None, "timings": {"total": 2.0}, "model_sha256": sha}

    rs = [rec("drill", f"drill_{i}", m, "new") for i in range(2) for m in ("latent", "nearest")]
    rs += [rec("mug", f"mug_{i}", "latent", "new") for i in range(2)]
    rs += [rec("mug", f"mug_{i}", "nearest", "new" if i else "old") for i in range(2)]  # one trial of the old model
    rs += [rec("tankard", "tankard_0", m, "own") for m in ("latent", "nearest")]
    committed = {"drill": "new", "mug": "new"}
    summary = summary_table(rs, committed=committed)
    assert "| `test` | drill | 2 |" in summary and "| `test` | mug † | 2 |" in summary
    assert "| `test` | tankard | 1 |" in summary
    assert "† some of the row's trials were run with another model" in summary
    assert summary_table(rs) == summary_table(rs, committed={})  # nothing to compare with: nothing marked
    assert "†" not in summary_table(rs)
    full = benchmark_tables(rs, committed=committed)
    assert "**mug, single view** († 1 of these 4 trials were run with another mug model" in full
    assert "**drill, single view**\n" in full
    assert markdown_tables(rs, committed)["summary"] == summary
