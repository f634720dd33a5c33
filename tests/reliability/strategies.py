"""Generators of bad inputs shared by the fuzz tests.

Every strategy draws ``(label, value)``: ``label`` names the input class
(e.g. ``"cloud:nan"``) for the reports; ``value`` is the input. Arrays are
built with numpy from a drawn seed and a few drawn parameters (fast, and
large enough to matter), not element by element.

Input classes (the issue's list): empty, one or two points, NaN/inf,
duplicate points, huge and tiny coordinates, millimetre units, far from the
origin (1 km), all points on a line or a plane, wrong dtypes and shapes,
nested lists, float32/int input, and valid clouds (so that the entry points'
other arguments are exercised too); files: missing, empty, truncated,
corrupted, of another format version or category; meshes: non-watertight,
self-intersecting, degenerate, millimetre, NaN vertices.
"""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
from hypothesis import settings
from hypothesis import strategies as st

from .harness import CI_EXAMPLES

# ----------------------------------------------------------------------------- profile scaling


def scaled(n: int):
    """``settings`` with ``n`` examples in the ci profile, scaled by the loaded profile (nightly: 10n)."""
    factor = settings.default.max_examples / CI_EXAMPLES
    return settings(max_examples=max(1, int(round(n * factor))))


seeds = st.integers(0, 2**32 - 1)

# ----------------------------------------------------------------------------- clouds

#: Classes that must be rejected by any cloud input (nothing meaningful can come out).
MUST_REJECT = {"empty", "nan", "inf", "wrong_shape", "wrong_dtype", "none"}
#: Words a rejection of these classes must contain.
WORDS = {
    "empty": ("empty", "at least", "no points"),
    "one_point": ("at least", "points", "empty"),
    "two_points": ("at least", "points"),
    "nan": ("nan", "inf"),
    "inf": ("nan", "inf"),
    "millimetres": ("millimetre", "metres", "units", "spans"),
    "huge": ("millimetre", "metres", "units", "spans", "large", "coordinates"),
    "wrong_shape": ("shape", "expected", "(n, 3)"),
    "wrong_dtype": ("numeric", "expected", "dtype", "shape", "nan"),  # None in an object array reads as NaN
    "none": ("numeric", "expected", "shape"),
}


def _blob(rng, n, size=0.05):
    """A hand-sized blob of n points around (0, 0, size) (metres)."""
    return rng.normal(0.0, size, (n, 3)) * np.array([0.5, 1.0, 1.5]) + np.array([0.0, 0.0, 2 * size])


@st.composite
def clouds(draw, *, min_n: int = 3, max_n: int = 120, valid_weight: int = 3, exclude=()):
    """``(label, cloud)`` over the bad-cloud classes (and valid clouds, ``valid_weight`` times as often)."""
    classes = ["valid"] * valid_weight + [
        "empty", "one_point", "two_points", "nan", "inf", "duplicates", "repeated_rows", "huge", "tiny",
        "millimetres", "far_1km", "line", "plane", "wrong_shape", "wrong_dtype", "none", "nested_list",
        "float32", "int", "noisy_outliers",
    ]
    classes = [c for c in classes if c not in exclude]
    kind = draw(st.sampled_from(classes))
    rng = np.random.default_rng(draw(seeds))
    n = draw(st.integers(min_n, max_n))
    base = _blob(rng, n)
    if kind == "valid":
        return kind, base
    if kind == "empty":
        return kind, np.zeros((0, 3))
    if kind == "one_point":
        return kind, base[:1]
    if kind == "two_points":
        return kind, _blob(rng, 2)
    if kind == "nan":
        a = base.copy()
        a[rng.integers(0, n, size=max(1, n // 10)), rng.integers(0, 3)] = np.nan
        return kind, a
    if kind == "inf":
        a = base.copy()
        a[rng.integers(0, n), rng.integers(0, 3)] = draw(st.sampled_from([np.inf, -np.inf]))
        return kind, a
    if kind == "duplicates":
        return kind, np.repeat(base[:1], n, axis=0)
    if kind == "repeated_rows":
        return kind, np.repeat(base[: max(2, n // 4)], 4, axis=0)
    if kind == "huge":
        return kind, base * 10.0 ** draw(st.integers(5, 300))
    if kind == "tiny":
        return kind, base * 10.0 ** -draw(st.integers(10, 300))
    if kind == "millimetres":
        return kind, base * 1000.0
    if kind == "far_1km":
        return kind, base + rng.normal(0.0, 1.0, 3) / np.sqrt(3.0) * 1000.0
    if kind == "line":
        d = rng.normal(size=3)
        return kind, rng.uniform(-0.1, 0.1, (n, 1)) * d / np.linalg.norm(d) + base[0]
    if kind == "plane":
        a = base.copy()
        a[:, draw(st.integers(0, 2))] = 0.0
        return kind, a
    if kind == "wrong_shape":
        shape = draw(st.sampled_from([(n, 2), (n, 4), (3, n + 4), (n,), (n, 3, 1), (), (1, n, 3)]))
        return kind, rng.normal(0.0, 0.05, shape)
    if kind == "wrong_dtype":
        v = draw(st.sampled_from(["strings", "object", "complex", "bytes", "str", "dict", "ragged"]))
        if v == "strings":
            return kind, np.array([["a", "b", "c"]] * n)
        if v == "object":
            a = base.astype(object)
            a[0, 0] = None
            return kind, a
        if v == "complex":
            return kind, base + 1j
        if v == "bytes":
            return kind, base.tobytes()
        if v == "str":
            return kind, "points.pcd"
        if v == "dict":
            return kind, {"x": base[:, 0]}
        return kind, [[0.0, 0.0, 0.0], [1.0, 2.0]]
    if kind == "none":
        return kind, None
    if kind == "nested_list":
        return kind, base.tolist()
    if kind == "float32":
        return kind, base.astype(np.float32)
    if kind == "int":
        return kind, (rng.integers(-1, 2, (n, 3))).astype(np.int64)
    if kind == "noisy_outliers":
        return kind, np.vstack([base, rng.uniform(-0.5, 0.5, (n, 3))])
    raise AssertionError(kind)


# ----------------------------------------------------------------------------- numbers


BAD_NUMBERS = (
    ("nan", float("nan")), ("inf", float("inf")), ("-inf", float("-inf")), ("zero", 0.0),
    ("negative", -1.0), ("huge", 1e300), ("tiny", 1e-300), ("string", "abc"), ("none", None),
    ("bool", True), ("array", np.ones(3)), ("complex", 1 + 1j), ("numeric_string", "0.5"),
    ("fraction", 2.5), ("big_int", 10**400),
)


def bad_numbers(*, valid=st.nothing()):
    """``(label, value)`` for scalar parameters: NaN, inf, 0, negative, huge, tiny, strings, None,
    bool, arrays -- plus ``valid`` values."""
    return st.one_of(valid.map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS))


def number(valid):
    """An option spec for :func:`options`: ``valid`` values, or any of :data:`BAD_NUMBERS`."""
    return valid, st.sampled_from(BAD_NUMBERS)


def choice(valid: list, bad: list):
    """An option spec for :func:`options` from explicit lists (``bad`` of ``(label, value)``)."""
    return st.sampled_from(valid), st.sampled_from(bad)


@st.composite
def options(draw, spec: dict, *, max_valid: int = 4, max_bad: int = 1):
    """Keyword arguments ``{name: (label, value)}``: up to ``max_valid`` options with valid values, then
    up to ``max_bad`` of them (or others) replaced by bad ones -- one problem at a time, mostly."""
    keys = sorted(spec)
    chosen = draw(st.lists(st.sampled_from(keys), unique=True, max_size=max_valid))
    out = {k: ("valid", draw(spec[k][0])) for k in chosen}
    n_bad = draw(st.integers(0, max_bad))
    for k in draw(st.lists(st.sampled_from(keys), unique=True, min_size=n_bad, max_size=n_bad)):
        out[k] = draw(spec[k][1])
    return out


# ----------------------------------------------------------------------------- poses


@st.composite
def poses(draw, *, single_ok: bool = True):
    """``(label, X)``: (K, 4, 4) or (4, 4) homogeneous transforms, valid and bad."""
    from catgrasp_drake.core.rotations import sample_rotations_within

    rng = np.random.default_rng(draw(seeds))
    k = draw(st.integers(1, 5))
    X = np.tile(np.eye(4), (k, 1, 1))
    X[:, :3, :3] = sample_rotations_within(rng, k, np.pi)
    X[:, :3, 3] = rng.normal(0.0, 0.05, (k, 3)) + np.array([0.0, 0.0, 0.1])
    kind = draw(st.sampled_from(["valid", "valid", "valid", "single", "nan", "inf", "wrong_shape", "scaled",
                                 "reflection", "singular", "far_1km", "huge", "empty", "string", "zero_matrix"]))
    if kind == "valid":
        return kind, X
    if kind == "single":
        return kind, X[0] if single_ok else X
    if kind == "nan":
        X[0, draw(st.integers(0, 2)), draw(st.integers(0, 3))] = np.nan
    elif kind == "inf":
        X[0, 0, 3] = np.inf
    elif kind == "wrong_shape":
        return kind, rng.normal(size=draw(st.sampled_from([(k, 3, 3), (k, 4, 3), (4,), (k, 16), (2, k, 4, 4)])))
    elif kind == "scaled":
        X[:, :3, :3] *= 2.0
    elif kind == "reflection":
        X[:, :3, 0] *= -1.0
    elif kind == "singular":
        X[:, :3, 2] = 0.0
    elif kind == "far_1km":
        X[:, :3, 3] += 1000.0
    elif kind == "huge":
        X[:, :3, 3] = 1e300
    elif kind == "empty":
        return kind, np.zeros((0, 4, 4))
    elif kind == "string":
        return kind, "identity"
    elif kind == "zero_matrix":
        X[:] = 0.0
    return kind, X


@st.composite
def latents(draw, q: int):
    """``(label, x)`` for a q-dimensional latent vector: valid, large, NaN/inf, wrong length/shape/dtype."""
    rng = np.random.default_rng(draw(seeds))
    kind = draw(st.sampled_from(["valid", "valid", "zero", "large", "huge", "nan", "inf", "short", "long",
                                 "scalar", "batch", "string", "list", "int", "none"]))
    x = rng.normal(size=q)
    if kind == "valid":
        return kind, x
    if kind == "zero":
        return kind, np.zeros(q)
    if kind == "large":
        return kind, x * 50.0
    if kind == "huge":
        return kind, x * 1e200
    if kind == "nan":
        x[0] = np.nan
        return kind, x
    if kind == "inf":
        x[-1] = np.inf
        return kind, x
    if kind == "short":
        return kind, x[:-1]
    if kind == "long":
        return kind, np.append(x, 1.0)
    if kind == "scalar":
        return kind, 0.5
    if kind == "batch":
        return kind, rng.normal(size=(2, q))
    if kind == "string":
        return kind, "latent"
    if kind == "list":
        return kind, x.tolist()
    if kind == "int":
        return kind, np.zeros(q, dtype=np.int64)
    return kind, None


# ----------------------------------------------------------------------------- bytes / files


def corrupt_bytes(data: bytes, rng: np.random.Generator, how: str) -> bytes:
    """``data`` truncated, bit-flipped, zeroed in a block, or replaced by junk."""
    n = len(data)
    if n == 0 and how in ("truncated", "flipped", "zeroed"):
        return data
    if how == "truncated":
        return data[: int(rng.integers(0, max(1, n)))]
    if how == "flipped":
        b = bytearray(data)
        for i in rng.integers(0, n, size=max(1, n // 5000)):
            b[i] ^= 1 << int(rng.integers(0, 8))
        return bytes(b)
    if how == "zeroed":
        b = bytearray(data)
        lo = int(rng.integers(0, n))
        b[lo: lo + int(rng.integers(1, 4096))] = b"\0" * len(b[lo: lo + 4096])
        return bytes(b[:n])
    if how == "junk":
        return rng.integers(0, 256, size=int(rng.integers(1, 4096)), dtype=np.uint8).tobytes()
    if how == "empty":
        return b""
    if how == "text":
        return b"this is not a point cloud\n" * int(rng.integers(1, 20))
    raise AssertionError(how)


CORRUPTIONS = ("truncated", "flipped", "zeroed", "junk", "empty", "text")


def npz_with_header(arrays: dict, header: dict) -> bytes:
    """An .npz archive with a ``__header__`` JSON array (as core/fileio.py writes) -- for forging headers."""
    buf = io.BytesIO()
    h = np.frombuffer(json.dumps(header).encode("utf-8"), dtype=np.uint8)
    np.savez(buf, __header__=h, **arrays)
    return buf.getvalue()


def zip_without_header(arrays: dict) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def pickled_npz() -> bytes:
    """An .npz holding an object array (would need pickle to load)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        inner = io.BytesIO()
        np.save(inner, np.array([{"evil": 1}], dtype=object), allow_pickle=True)
        z.writestr("__header__.npy", inner.getvalue())
    return buf.getvalue()
