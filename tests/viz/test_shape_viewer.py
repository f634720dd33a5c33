"""ShapeViewer (Meshcat sliders over the latent shape space) and ``catgrasp view``.

The model is built without simulation: a 3-drill shape space and a regressor
that predicts the hand-written drill grasp for every x. What Meshcat holds is
read back from Drake's packed (msgpack) scene messages, so the tests check
what a browser would receive, not only the viewer's own bookkeeping.
"""

from __future__ import annotations

import base64
import dataclasses
import re
import struct

import numpy as np
import pytest

from catgrasp_drake import cli
from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.regression import LinearRegressor, fit_ridge
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.data.dataset import instance_clouds
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import descriptor_vector
from catgrasp_drake.robot.models import HAND_BASE_LINK
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.viz.meshcat_tools import start_meshcat
from catgrasp_drake.viz.shape_viewer import INSTANCE_SLIDER, SLIDER_STEP, ShapeViewer, latent_slider_names

NAMES = ("drill_00", "drill_05", "drill_07")


@pytest.fixture(scope="module")
def model() -> CategoryModel:
    clouds = instance_clouds("drill", list(NAMES), 0.015)
    space = build_shape_space(clouds, canonical_index=0)
    template = load_handwritten_motion("drill", "drill_00")
    regressor = fit_ridge(space.latent_train, np.tile(descriptor_vector(template), (len(NAMES), 1)), alpha=1e-2)
    return CategoryModel(category="drill", space=space, regressor=regressor, template=template,
                         instances=NAMES, canonical_instance="drill_00")


@pytest.fixture
def meshcat():
    return start_meshcat()


@pytest.fixture
def viewer(model, meshcat):
    return ShapeViewer(model, meshcat)


# --------------------------------------------------------------------------- reading Meshcat back


def _ext_payload(buf: bytes, i: int) -> bytes:
    """The payload of the msgpack ext value starting at ``buf[i]`` (ext8/16/32)."""
    width = {0xC7: 1, 0xC8: 2, 0xC9: 4}[buf[i]]
    n = int.from_bytes(buf[i + 1:i + 1 + width], "big")
    start = i + 1 + width + 1  # skip the ext type byte (Float32Array)
    return buf[start:start + n]


def meshcat_points(meshcat, path: str) -> np.ndarray:
    """The (N, 3) float32 positions of the point cloud Meshcat holds at ``path``."""
    packed = meshcat._GetPackedObject(path)
    i = packed.index(b"\xa8position")
    i = packed.index(b"\xa5array", i) + len(b"\xa5array")
    return np.frombuffer(_ext_payload(packed, i), dtype="<f4").reshape(-1, 3)


def meshcat_transform(meshcat, path: str) -> np.ndarray:
    """The 4x4 transform Meshcat holds for ``path`` (relative to its parent)."""
    packed = meshcat._GetPackedTransform(path)
    i = packed.index(b"matrix\xdc\x00\x10") + len(b"matrix\xdc\x00\x10")
    values = [struct.unpack(">d", packed[i + 9 * k + 1:i + 9 * k + 9])[0] for k in range(16)]
    return np.array(values).reshape(4, 4).T  # column-major


def html_commands(html: str) -> list[bytes]:
    """The packed scene commands embedded (base64) in a StaticHtml page."""
    return [base64.b64decode(b) for b in re.findall(r"base64,([A-Za-z0-9+/=]+)", html)]


# --------------------------------------------------------------------------- viewer


def test_starts_on_the_canonical_instance(viewer, model, meshcat):
    assert viewer.instance == 0
    np.testing.assert_array_equal(viewer.x, model.space.latent_train[0])
    assert set(meshcat.GetSliderNames()) == {*latent_slider_names(model.space.q), INSTANCE_SLIDER}
    assert not viewer.poll()  # nothing moved


def test_set_latent_draws_the_deformed_shape(viewer, model, meshcat):
    x = np.array([0.7, -1.3])[: model.space.q]
    viewer.set_latent(x)
    np.testing.assert_array_equal(viewer.points, model.space.deform(x))
    np.testing.assert_allclose(meshcat_points(meshcat, "/view/shape"), model.space.deform(x), atol=1e-6)
    # the canonical shape does not follow x
    np.testing.assert_allclose(meshcat_points(meshcat, "/view/canonical"), model.space.canonical, atol=1e-6)
    for name, v in zip(latent_slider_names(model.space.q), x):
        assert meshcat.GetSliderValue(name) == pytest.approx(v)
    assert viewer.instance is None
    with pytest.raises(InputError):
        viewer.set_latent(np.zeros(model.space.q + 1))


def test_grasp_triads_and_hand_follow_the_warped_motion(model, meshcat):
    # A regressor whose grasp moves with x (2 cm per unit of x1, along O's x), so that the
    # drawn triads must really follow x (the fixture's regressor predicts one grasp for all x).
    coef = model.regressor.coef.copy()
    grasp = model.template.pose_names.index("grasp")
    coef[9 * grasp:9 * grasp + 3, 0] = [0.02, 0.0, 0.0]
    moving = dataclasses.replace(model, regressor=LinearRegressor(coef, model.regressor.intercept, 0.0))
    viewer = ShapeViewer(moving, meshcat)
    poses = []
    for x in (np.array([-1.0, 2.0])[: model.space.q], np.array([1.5, -0.5])[: model.space.q]):
        viewer.set_latent(x)
        expected = moving.warped_motion(x)
        np.testing.assert_allclose(meshcat_transform(meshcat, "/view/grasp/grasp"), expected.pose("grasp"),
                                   atol=1e-12)
        np.testing.assert_allclose(meshcat_transform(meshcat, "/view/grasp/pregrasp"), expected.pose("pregrasp"),
                                   atol=1e-12)
        np.testing.assert_allclose(meshcat_transform(meshcat, f"/view/hand/{HAND_BASE_LINK}"),
                                   expected.pose("grasp"), atol=1e-9)
        np.testing.assert_array_equal(viewer.motion.poses, expected.poses)
        poses.append(expected.pose("grasp"))
    assert poses[1][0, 3] - poses[0][0, 3] == pytest.approx(0.05, abs=1e-3)  # 2.5 units of x1 * 2 cm


def test_show_instance_moves_the_sliders_and_draws_the_instance(viewer, model, meshcat):
    for k in (2, 1):
        viewer.show_instance(k)
        x_k = model.space.latent_train[k]
        sliders = [meshcat.GetSliderValue(n) for n in latent_slider_names(model.space.q)]
        np.testing.assert_allclose(sliders, x_k, atol=SLIDER_STEP / 2 + 1e-12)
        assert meshcat.GetSliderValue(INSTANCE_SLIDER) == k
        np.testing.assert_array_equal(viewer.points, model.space.deform(x_k))  # exact, not slider-rounded
        assert viewer.instance == k
        assert meshcat.HasPath(f"/view/instance/{NAMES[k]}")  # the instance's name is in the scene tree
        assert not viewer.poll()  # its own slider moves are not mistaken for user input
    viewer.show_instance("drill_07")
    assert viewer.instance == 2 and not meshcat.HasPath("/view/instance/drill_05")
    for bad in (3, -1, "drill_01", 1.0):
        with pytest.raises(InputError):
            viewer.show_instance(bad)


def test_poll_redraws_after_slider_changes(viewer, model, meshcat):
    meshcat.SetSliderValue("x1", 0.5)
    assert viewer.poll()
    x = np.array([meshcat.GetSliderValue(n) for n in latent_slider_names(model.space.q)])
    assert x[0] == pytest.approx(0.5)
    np.testing.assert_array_equal(viewer.x, x)
    np.testing.assert_array_equal(viewer.points, model.space.deform(x))
    np.testing.assert_allclose(meshcat_points(meshcat, "/view/shape"), model.space.deform(x), atol=1e-6)
    np.testing.assert_allclose(meshcat_transform(meshcat, "/view/grasp/grasp"),
                               model.warped_motion(x).pose("grasp"), atol=1e-12)
    assert viewer.instance is None
    assert not viewer.poll()  # redraws only on change

    meshcat.SetSliderValue(INSTANCE_SLIDER, 2)
    assert viewer.poll()
    assert viewer.instance == 2
    np.testing.assert_array_equal(viewer.points, model.space.deform(model.space.latent_train[2]))
    assert meshcat.GetSliderValue("x1") == pytest.approx(model.space.latent_train[2, 0], abs=SLIDER_STEP / 2)
    assert not viewer.poll()


def test_one_viewer_per_meshcat_until_closed(viewer, model, meshcat):
    with pytest.raises(InputError, match="already has sliders"):
        ShapeViewer(model, meshcat)
    viewer.close()
    assert meshcat.GetSliderNames() == [] and not meshcat.HasPath("/view/shape")
    ShapeViewer(model, meshcat, show_hand=False)
    assert not meshcat.HasPath("/view/hand")


def test_export_html_has_every_instance_under_its_own_toggle(viewer, model, meshcat, tmp_path):
    viewer.set_latent(np.full(model.space.q, 0.3))
    out = tmp_path / "sub" / "drill_space.html"
    out.parent.mkdir()
    viewer.export_html(out)
    html = out.read_text()
    assert html.startswith("<!DOCTYPE html>")
    commands = html_commands(html)
    for k, name in enumerate(NAMES):
        prefix = f"/view/instances/{name}".encode()
        for part in (b"/shape", b"/grasp/x", b"/hand/" + HAND_BASE_LINK.encode()):
            assert any(prefix + part in c for c in commands), (name, part)
        hidden = any(b"set_property" in c and prefix + b"\xa8property\xa7visible\xa5value\xc2" in c
                     for c in commands)
        assert hidden == (k > 0), name
    assert any(b"/view/canonical" in c for c in commands)
    assert not any(b"/view/shape" in c for c in commands)  # the live scene is not part of the page
    assert meshcat.HasPath("/view/shape") and not meshcat.HasPath("/view/instances")  # and it is untouched
    assert [p.name for p in out.parent.iterdir()] == ["drill_space.html"]  # no temporary left behind


# --------------------------------------------------------------------------- CLI


def test_cli_view_once_writes_html(model, tmp_path, capsys):
    path = tmp_path / "drill.npz"
    model.save(path)
    html = tmp_path / "view.html"
    assert cli.main(["view", "drill", "--model", str(path), "--once", "--html", str(html)]) == 0
    out = capsys.readouterr().out
    assert "http://localhost:" in out and str(html) in out
    text = html.read_text()
    assert all(any(f"/view/instances/{n}".encode() in c for c in html_commands(text)) for n in NAMES)


@pytest.mark.parametrize("argv, expected", [
    (["view", "drill", "--model", "{tmp}/missing.npz", "--once"], "missing.npz: no trained model"),
    (["view", "teapot", "--once"], "unknown category 'teapot'"),
    (["view", "mug", "--model", "{tmp}/drill.npz", "--once"], "is a 'drill' model, not 'mug'"),
])
def test_cli_view_errors_are_one_line(model, tmp_path, capsys, argv, expected):
    model.save(tmp_path / "drill.npz")
    argv = [a.format(tmp=tmp_path) for a in argv]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("catgrasp: error:") and expected in err
    assert len(err.splitlines()) == 1
