"""Meshcat helpers and headless rendering."""

from __future__ import annotations

import numpy as np

from catgrasp_drake.data.dataset import instance_mesh_path
from catgrasp_drake.viz.meshcat_tools import COLORS, draw_cloud, draw_triad, save_static_html, start_meshcat
from catgrasp_drake.viz.render import render_mesh


def test_meshcat_is_local_and_exports_a_self_contained_page(tmp_path):
    empty = len(start_meshcat().StaticHtml())
    meshcat = start_meshcat()
    assert meshcat.web_url().startswith("http://localhost:")
    draw_cloud(meshcat, "/catgrasp/observed", np.random.default_rng(0).normal(size=(50, 3)) * 0.05, COLORS["observed"])
    draw_triad(meshcat, "/catgrasp/grasp", np.eye(4))
    assert meshcat.HasPath("/catgrasp/observed") and meshcat.HasPath("/catgrasp/grasp/z")
    out = tmp_path / "scene.html"
    save_static_html(meshcat, out)
    html = out.read_text()
    assert html.startswith("<!DOCTYPE html>") and "<script" in html
    assert len(html) > empty + 1000  # the scene is embedded (msgpack, base64) in the page


def test_headless_render_shows_the_object():
    img = render_mesh(instance_mesh_path("drill", "drill_00"), size=(96, 96))
    assert img.shape == (96, 96, 3)
    background = np.all(img > 240, axis=2)
    assert 0.1 < 1 - background.mean() < 0.8  # the drill covers part of the image, not all of it
