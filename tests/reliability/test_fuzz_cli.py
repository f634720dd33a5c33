"""Fuzzing the ``catgrasp`` command line (cli.main) with bad arguments, in-process.

Every generated argv holds at least one bad argument (unknown category or instance, a bad number,
a missing, corrupt, forged or other-category model file, an unknown sub-command or option); it
must end with a non-zero exit code and one line ``catgrasp...: error: ...`` on stderr, never a
traceback. The jobs' heavy entry points (training, evaluation, the demo's diagram, data
generation, Meshcat) are replaced by a tripwire for the test, so an argv the CLI failed to reject
fails at once instead of starting a real run.
"""

from __future__ import annotations

import contextlib
import io
import shutil

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake import cli

from .conftest import TRAINED
from .harness import RECORDS, check_message
from .strategies import corrupt_bytes, scaled, seeds


class WouldRun(AssertionError):
    """Raised by a tripwire: the CLI accepted a bad argv and started a real job."""


def _tripwire(name):
    def trip(*args, **kwargs):
        raise WouldRun(f"{name} was started")
    return trip


@pytest.fixture(scope="module", autouse=True)
def tripwires():
    mp = pytest.MonkeyPatch()
    import catgrasp_drake.data.dataset as dataset
    import catgrasp_drake.evaluation as evaluation
    import catgrasp_drake.training as training
    import catgrasp_drake.transfer as transfer
    import catgrasp_drake.viz.meshcat_tools as meshcat_tools

    for mod, name in [(training, "train_category"), (evaluation, "evaluate"), (transfer, "make_transfer_diagram"),
                      (transfer, "run_transfer"), (dataset, "generate_dataset"), (dataset, "instance_clouds"),
                      (meshcat_tools, "start_meshcat")]:
        mp.setattr(mod, name, _tripwire(f"{mod.__name__}.{name}"))
    try:
        import catgrasp_drake.viz.sheets as sheets

        mp.setattr(sheets, "dataset_contact_sheet", _tripwire("dataset_contact_sheet"))
    except ImportError:
        pass
    yield
    mp.undo()


BAD_INTS = ["abc", "nan", "-1", "0", "1.5", "", "1e400", "99999999999999999999999", "-0"]
BAD_FLOATS = ["abc", "nan", "inf", "-inf", "-1", "", "1e400", "0"]
NAMES = st.one_of(st.sampled_from(["teapot", "", " ", "drill ", "DRILL", "../drill", "drill\nmug", "-x", "mug_99",
                                   "spray-bottle", "ünïcode", "a" * 300]),
                  st.text(min_size=1, max_size=20).filter(lambda s: s not in ("drill", "mug", "spray_bottle")
                                                          and not s.startswith("-")))


@st.composite
def model_files(draw, tmp):
    """``(label, path)`` of a --model argument that must be refused."""
    rng = np.random.default_rng(draw(seeds))
    how = draw(st.sampled_from(["missing", "directory", "empty", "truncated", "junk", "text", "other_category",
                                "npy_file", "other_version"]))
    path = tmp / f"model{draw(seeds)}.npz"
    raw = TRAINED["mug"].read_bytes()
    if how == "directory":
        path.mkdir()
    elif how in ("empty", "truncated", "junk", "text"):
        path.write_bytes(corrupt_bytes(raw, rng, how))
    elif how == "other_category":
        path.write_bytes(raw)  # a mug model passed for a drill or spray bottle
    elif how == "npy_file":
        buf = io.BytesIO()
        np.save(buf, np.zeros(3))
        path.write_bytes(buf.getvalue())
    elif how == "other_version":
        import json

        from .strategies import npz_with_header

        with np.load(io.BytesIO(raw)) as z:
            arrays = {k: z[k] for k in z.files}
        header = json.loads(arrays.pop("__header__").tobytes().decode())
        header["format_version"] = 2
        path.write_bytes(npz_with_header(arrays, header))
    return how, str(path)


@st.composite
def bad_argv(draw, tmp):
    """``(label, argv)`` with at least one bad argument."""
    cat = draw(st.sampled_from(["drill", "spray_bottle", "mug"]))
    kind = draw(st.sampled_from([
        "no_command", "unknown_command", "unknown_option", "train:category", "train:samples", "train:seed",
        "train:workers", "train:hold_out", "train:instances", "train:canonical", "evaluate:category",
        "evaluate:method", "evaluate:view", "evaluate:folds", "evaluate:instances", "evaluate:samples",
        "evaluate:seed", "evaluate:workers", "clouds:category", "clouds:voxel", "clouds:format", "demo:category",
        "demo:model", "demo:min_confidence", "demo:seed", "demo:view", "demo:instance", "view:category",
        "view:model", "generate-data:seed", "contact-sheet:categories",
    ]))
    bad_int, bad_float, name = draw(st.sampled_from(BAD_INTS)), draw(st.sampled_from(BAD_FLOATS)), draw(NAMES)
    if kind == "no_command":
        return kind, []
    if kind == "unknown_command":
        return kind, [draw(st.sampled_from(["fit", "trian", "", "--", "-v", "grasp"]))]
    if kind == "unknown_option":
        return kind, [draw(st.sampled_from(["train", "evaluate", "demo", "view", "clouds"])), cat,
                      draw(st.sampled_from(["--smaples", "--gpu", "--verbose", "-x"])), "1"]
    cmd, what = kind.split(":")
    if cmd == "train":
        argv = ["train", cat, "--out", str(tmp / "m.npz"), "--cache", str(tmp / "cache")]
        if what == "category":
            argv[1] = name
        elif what in ("samples", "seed", "workers", "hold_out"):
            value = bad_int
            if value in ("0", "-0") and what in ("seed", "hold_out", "workers"):  # 0 is valid there
                value = "-1"
            if what == "hold_out" and value not in ("-1",):
                value = draw(st.sampled_from([value, "99"]))
            argv += [f"--{what.replace('_', '-')}", value]
        elif what == "instances":
            argv += ["--instances", f"{cat}_00", name]
        elif what == "canonical":
            argv += ["--canonical", name]
        return kind, argv
    if cmd == "evaluate":
        argv = ["evaluate", cat, "--out", str(tmp / "eval")]
        if what == "category":
            argv[1] = name
        elif what == "method":
            argv += ["--methods", "latent", name]
        elif what == "view":
            argv += ["--views", name]
        elif what in ("folds", "samples", "workers"):
            argv += [f"--{what}", bad_int if bad_int not in ("0", "-0") or what == "samples" else "-1"]
        elif what == "seed":
            argv += ["--seed", draw(st.sampled_from(["-1", "abc", "1.5", ""]))]
        elif what == "instances":
            argv += ["--instances", name]
        return kind, argv
    if cmd == "clouds":
        argv = ["clouds", cat, "--out", str(tmp / "clouds")]
        if what == "category":
            argv[1] = name
        elif what == "voxel":
            argv += ["--voxel", bad_float]
        else:
            argv += ["--format", draw(st.sampled_from(["xyz", "PCD", "", "obj"]))]
        return kind, argv
    if cmd == "demo":
        argv = ["demo", "--category", cat, "--out", str(tmp / "demo"), "--no-meshcat"]
        if what == "category":
            argv[2] = name
        elif what == "model":
            how, path = draw(model_files(tmp))
            if how == "other_category" and cat == "mug":
                argv[2] = "drill"
            argv += ["--model", path]
            kind = f"demo:model_{how}"
        elif what == "min_confidence":
            argv += ["--min-confidence", draw(st.sampled_from(["abc", "nan", "inf", "-0.1", "1.5", ""]))]
        elif what == "seed":
            argv += ["--seed", draw(st.sampled_from(["-1", "abc", "1.5"]))]
        elif what == "view":
            argv += ["--view", name]
        elif what == "instance":
            argv += ["--instance", name]
        return kind, argv
    if cmd == "view":
        argv = ["view", cat, "--once"]
        if what == "category":
            argv[1] = name
        else:
            how, path = draw(model_files(tmp))
            if how == "other_category" and cat == "mug":
                argv[1] = "drill"
            argv += ["--model", path]
            kind = f"view:model_{how}"
        return kind, argv
    if cmd == "generate-data":
        return kind, ["generate-data", "--out", str(tmp / "data"), "--seed", draw(st.sampled_from(["-1", "abc", "1.5",
                                                                                                  ""]))]
    return kind, ["contact-sheet", "--out", str(tmp / "sheet.png"), "--categories", "drill", name]


@scaled(150)
@given(data=st.data())
def test_cli_rejects_bad_arguments(tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("cli")
    label, argv = data.draw(bad_argv(tmp))
    out, err = io.StringIO(), io.StringIO()
    import time

    t0 = time.perf_counter()
    status, message = "crash", ""
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = cli.main(argv)
            except SystemExit as e:  # argparse
                code = e.code
        text = err.getvalue()
        lines = [ln for ln in text.splitlines() if ln.strip()]
        assert code not in (0, None), f"argv {argv!r} was accepted (exit code {code})"
        assert "Traceback" not in text, f"argv {argv!r} printed a traceback:\n{text}"
        errors = [ln for ln in lines if "error:" in ln]
        assert len(errors) == 1 and lines[-1] == errors[0] and errors[0].startswith("catgrasp"), \
            f"argv {argv!r}: expected one 'catgrasp...: error: ...' line last on stderr, got {text!r}"
        message = errors[0]
        check_message(ValueError(message.split("error:", 1)[1].strip() + " (cli)"))
        status = "rejected"
    finally:
        RECORDS.append({"entry": "cli.main", "label": label, "outcome": status,
                        "seconds": time.perf_counter() - t0, "message": message[:300]})
        shutil.rmtree(tmp, ignore_errors=True)


def test_the_progress_bar_says_how_long_is_left(monkeypatch, capsys):
    """Half the trials done in 60 s: the bar says ~1 min left; done: no estimate, a newline."""
    from catgrasp_drake import cli

    clock = iter([0.0, 0.0, 60.0, 7260.0, 7300.0])  # the bar made, its stage started, then one reading per call
    monkeypatch.setattr(cli.time, "perf_counter", lambda: next(clock))
    bar = cli._Progress()
    bar("trials", 5, 10)
    assert "5/10 (0.08/s, ~1 min left)" in capsys.readouterr().err
    bar("trials", 6, 1000)  # 6 in 7260 s: 994 more take 1.2e6 s
    assert "(0.00/s, ~334 h 6 min left)" in capsys.readouterr().err
    bar("trials", 1000, 1000)
    err = capsys.readouterr().err
    assert "1000/1000" in err and "left" not in err and err.endswith("\n")
    assert [cli._time_left(s) for s in (0.2, 59.0, 90.0, 3599.0, 3600.0, 5400.0)] == \
        ["~1 s", "~59 s", "~2 min", "~1 h 0 min", "~1 h 0 min", "~1 h 30 min"]
