"""Security and file hygiene, by reading the source (AST) and by trying the dangerous inputs.

Rules, for every ``.py`` under ``catgrasp_drake/``, ``diagrams/`` and ``benchmarks/``:

* no pickle: no ``pickle``/``dill``/``shelve``/``marshal``/``joblib``/``cloudpickle`` import, no
  ``allow_pickle`` other than ``False``, every ``np.load`` says ``allow_pickle=False``, no
  ``read_pickle``/``torch.load``;
* no code from data: no ``eval``/``exec``/``compile``/``__import__`` call;
* YAML only through ``yaml.safe_load`` (or ``yaml.load(..., Loader=SafeLoader)``);
* no shell: no ``shell=True``, ``os.system``/``os.popen``/``os.exec*``/``os.spawn*``; the package itself
  runs no command at all (no ``subprocess``), and scripts pass argument lists, never a command string;
* servers on localhost only: ``Meshcat(...)`` only as ``Meshcat(MeshcatParams(host="localhost", ...))``,
  no ``StartMeshcat``, no ``"0.0.0.0"``; a Ray head started by the project (``ray.init`` without an
  ``address``) binds ``_node_ip_address="127.0.0.1"`` with no dashboard;
* model and result files only through ``core.fileio``'s atomic writes: no ``open(..., "w")``,
  ``write_text``/``write_bytes``, ``json.dump``, ``np.save*`` to a path, ``savefig``, image
  ``.save(path)`` outside the few listed (and justified) exceptions.

Each rule is also checked on a snippet that breaks it, so a scanner that went blind would fail too.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from catgrasp_drake.errors import InputError, ModelFileError

REPO = Path(__file__).resolve().parents[2]
SCANNED = ("catgrasp_drake", "diagrams", "benchmarks", "tools")
#: The package runs no command; scripts may (argument lists only).
NO_SUBPROCESS = ("catgrasp_drake",)
#: Non-atomic writes that are not model/result files, each with its reason.
WRITE_EXCEPTIONS = {
    ("catgrasp_drake/core/fileio.py", "*"): "the atomic writer itself (writes a temporary file, then renames)",
    ("catgrasp_drake/viz/sheets.py", "write_bytes"): "a scratch region mesh in a TemporaryDirectory, only rendered",
    ("catgrasp_drake/data/cloud_io.py", "write_point_cloud"):
        "open3d writes into a TemporaryDirectory; the bytes are then written with atomic_write_bytes",
}
#: Receivers whose ``.save(path)`` is the project's own atomic model writer (core.fileio.save_arrays).
ATOMIC_SAVERS = {"model", "space", "train_category", "build_shape_space", "CategoryModel", "ShapeSpace"}

FORBIDDEN_MODULES = {"pickle", "cPickle", "_pickle", "dill", "shelve", "marshal", "joblib", "cloudpickle"}
UNSAFE_YAML = {"load", "load_all", "full_load", "full_load_all", "unsafe_load", "unsafe_load_all"}
UNSAFE_YAML_LOADERS = {"Loader", "UnsafeLoader", "FullLoader"}
LOCAL_HOSTS = {"localhost", "127.0.0.1", "::1"}


def _name(node) -> str:
    """Dotted name of a Name/Attribute chain (``np.lib.format`` -> "np.lib.format"), else ""."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        base = _name(node.value)
        return f"{base}.{node.attr}" if base else f"?.{node.attr}"
    if isinstance(node, ast.Call):
        return _name(node.func) + "()"
    return ""


def _kw(call: ast.Call, name: str):
    for k in call.keywords:
        if k.arg == name:
            return k.value
    return None


def _const(node, value) -> bool:
    return isinstance(node, ast.Constant) and node.value == value


def scan_source(text: str, rel: str) -> list[str]:
    """Every rule broken by the source ``text`` of file ``rel`` (repository-relative), as "rel:line: what"."""
    tree = ast.parse(text, filename=rel)
    found = []

    def bad(node, what):
        found.append(f"{rel}:{getattr(node, 'lineno', 0)}: {what}")

    package = rel.split("/", 1)[0]
    for node in ast.walk(tree):
        # ---------------------------------------------------------------- imports
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            for m in mods:
                if m.split(".")[0] in FORBIDDEN_MODULES:
                    bad(node, f"imports {m} (pickle-like deserialisation)")
                if m.split(".")[0] == "subprocess" and package in NO_SUBPROCESS:
                    bad(node, "the package imports subprocess (it must run no command)")
            if isinstance(node, ast.ImportFrom) and node.module == "os":
                for a in node.names:
                    if a.name in ("system", "popen") or a.name.startswith(("exec", "spawn")):
                        bad(node, f"imports os.{a.name}")
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("pydrake"):
                if any(a.name == "StartMeshcat" for a in node.names):
                    bad(node, "StartMeshcat (may bind all interfaces); use viz.meshcat_tools.start_meshcat")
        if isinstance(node, ast.Constant) and node.value == "0.0.0.0":
            bad(node, f"binds all interfaces ({node.value!r})")
        if isinstance(node, ast.Attribute) and node.attr in UNSAFE_YAML_LOADERS and _name(node.value) == "yaml":
            bad(node, f"yaml.{node.attr} (unsafe YAML loader)")
        if not isinstance(node, ast.Call):
            continue
        # ---------------------------------------------------------------- calls
        fn = _name(node.func)
        last = fn.rsplit(".", 1)[-1]
        if fn in ("eval", "exec", "compile", "__import__"):
            bad(node, f"{fn}() runs code from data")
        ap = _kw(node, "allow_pickle")
        if ap is not None and not _const(ap, False):
            bad(node, "allow_pickle is not False")
        if fn in ("np.load", "numpy.load") and not _const(ap, False):
            bad(node, "np.load without allow_pickle=False")
        if last in ("read_pickle", "to_pickle") or fn == "torch.load":
            bad(node, f"{fn}() (pickle)")
        if fn.startswith("yaml.") and last in UNSAFE_YAML:
            loader = _kw(node, "Loader")
            if not (last == "load" and loader is not None and _name(loader) in ("yaml.SafeLoader", "yaml.CSafeLoader",
                                                                                 "SafeLoader", "CSafeLoader")):
                bad(node, f"{fn}() without SafeLoader (use yaml.safe_load)")
        if _const(_kw(node, "shell"), True):
            bad(node, "shell=True")
        if fn in ("os.system", "os.popen", "pty.spawn") or re.fullmatch(r"os\.(exec|spawn)\w*", fn):
            bad(node, f"{fn}() runs a command")
        if fn.startswith("subprocess."):
            if package in NO_SUBPROCESS:
                bad(node, f"{fn}(): the package must run no command")
            elif node.args and isinstance(node.args[0], (ast.Constant, ast.JoinedStr, ast.BinOp)):
                bad(node, f"{fn}() with a command string (pass an argument list)")
        if last == "Meshcat":
            arg = node.args[0] if node.args else _kw(node, "params")
            host = _kw(arg, "host") if isinstance(arg, ast.Call) and _name(arg.func).endswith("MeshcatParams") else None
            if not (isinstance(host, ast.Constant) and host.value in LOCAL_HOSTS):
                bad(node, "Meshcat(...) not created as Meshcat(MeshcatParams(host=\"localhost\", ...))")
        if last == "MeshcatParams":
            host = _kw(node, "host")
            if not (isinstance(host, ast.Constant) and host.value in LOCAL_HOSTS):
                bad(node, "MeshcatParams without host=\"localhost\"")
        if last == "StartMeshcat":
            bad(node, "StartMeshcat() (may bind all interfaces)")
        if fn == "ray.init" and _kw(node, "address") is None and not node.args:  # starts a head on this machine
            if not _const(_kw(node, "_node_ip_address"), "127.0.0.1"):
                bad(node, "ray.init starting a head without _node_ip_address=\"127.0.0.1\"")
            if not _const(_kw(node, "include_dashboard"), False):
                bad(node, "ray.init starting a head with its dashboard (a web server)")
        host_kw = _kw(node, "host")
        if isinstance(host_kw, ast.Constant) and host_kw.value not in LOCAL_HOSTS and isinstance(host_kw.value, str):
            bad(node, f"a server bound to host={host_kw.value!r}")
        # ---------------------------------------------------------------- non-atomic writes (package + diagrams)
        if package == "benchmarks":
            continue
        write = None
        if fn == "open" or fn.endswith(".open") and fn != "os.fdopen":
            mode = node.args[1] if len(node.args) > 1 else _kw(node, "mode")
            if isinstance(mode, ast.Constant) and isinstance(mode.value, str) and set(mode.value) & set("wax+"):
                write = "open"
        elif last in ("write_text", "write_bytes"):
            write = last
        elif fn in ("json.dump", "yaml.dump", "yaml.safe_dump") and len(node.args) >= 2:
            write = fn
        elif fn in ("np.save", "np.savez", "np.savez_compressed", "np.savetxt", "numpy.save", "numpy.savez",
                    "numpy.savez_compressed", "numpy.savetxt"):
            if not (node.args and isinstance(node.args[0], ast.Name) and node.args[0].id in ("buf", "buffer")):
                write = fn
        elif last in ("savefig", "tofile", "to_csv", "to_json", "imwrite", "export", "write_html"):
            write = last
        elif re.fullmatch(r"(o3d|open3d)\.io\.write_\w+", fn):
            write = "write_point_cloud" if "point_cloud" in fn else last
        elif last == "save" and _kw(node, "format") is None:
            receiver = ""
            if isinstance(node.func, ast.Attribute):
                receiver = _name(node.func.value).rstrip("()").rsplit(".", 1)[-1]
            if receiver not in ATOMIC_SAVERS:
                write = "save"
        if write and (rel, "*") not in WRITE_EXCEPTIONS and (rel, write) not in WRITE_EXCEPTIONS:
            bad(node, f"non-atomic file write ({write}); use core.fileio.atomic_write_bytes/_text or save_arrays")
    return found


def _sources():
    for top in SCANNED:
        for p in sorted((REPO / top).rglob("*.py")):
            if "__pycache__" not in p.parts:
                yield p


def test_the_source_follows_the_security_and_file_rules():
    files = list(_sources())
    assert len(files) > 40
    findings = [f for p in files for f in scan_source(p.read_text(), str(p.relative_to(REPO)))]
    assert findings == []


def test_the_write_exceptions_still_exist():
    """An exception whose file no longer holds the write is stale: remove it."""
    for (rel, what), why in WRITE_EXCEPTIONS.items():
        text = (REPO / rel).read_text()
        assert what == "*" or what in text, (rel, what, why)


# every rule must catch its own breach
_BREACHES = {
    "import pickle\npickle.loads(b'')": "imports pickle",
    "from joblib import load": "imports joblib",
    "import numpy as np\nnp.load('x.npy')": "np.load without allow_pickle=False",
    "import numpy as np\nnp.load('x.npz', allow_pickle=True)": "allow_pickle is not False",
    "eval(open('f').read())": "eval() runs code",
    "exec(text)": "exec() runs code",
    "import yaml\nyaml.load(text)": "without SafeLoader",
    "import yaml\nyaml.load(text, Loader=yaml.FullLoader)": "unsafe YAML loader",
    "import yaml\nyaml.unsafe_load(text)": "without SafeLoader",
    "import os\nos.system(cmd)": "os.system() runs a command",
    "import subprocess\nsubprocess.run(cmd, shell=True)": "shell=True",
    "from pydrake.geometry import Meshcat\nm = Meshcat()": "Meshcat(...) not created",
    "from pydrake.geometry import Meshcat, MeshcatParams\nm = Meshcat(MeshcatParams(port=7000))": "without host",
    "from pydrake.geometry import Meshcat, MeshcatParams\nm = Meshcat(MeshcatParams(host='0.0.0.0'))": "all interfaces",
    "from pydrake.geometry import StartMeshcat": "StartMeshcat",
    "import ray\nray.init(num_cpus=2)": "without _node_ip_address",
    "import ray\nray.init(_node_ip_address='127.0.0.1')": "with its dashboard",
    "open(path, 'w').write(text)": "non-atomic file write (open)",
    "path.write_text(json.dumps(x))": "non-atomic file write (write_text)",
    "import json\njson.dump(record, f)": "non-atomic file write (json.dump)",
    "import numpy as np\nnp.savez(path, a=1)": "non-atomic file write (np.savez)",
    "Image.fromarray(a).save(path)": "non-atomic file write (save)",
    "fig.savefig('x.png')": "non-atomic file write (savefig)",
    "mesh.export('drill.obj')": "non-atomic file write (export)",
}


@pytest.mark.parametrize("snippet", sorted(_BREACHES), ids=range(len(_BREACHES)))
def test_the_scanner_catches_each_breach(snippet):
    findings = scan_source(snippet, "catgrasp_drake/example.py")
    assert any(_BREACHES[snippet] in f for f in findings), findings


def test_the_scanner_accepts_the_safe_forms():
    safe = """
import io, json, yaml
import numpy as np
from pydrake.geometry import Meshcat, MeshcatParams
data = yaml.safe_load(text)
other = yaml.load(text, Loader=yaml.SafeLoader)
a = np.load(path, allow_pickle=False)
m = Meshcat(MeshcatParams(host="localhost", port=0))
buf = io.BytesIO()
np.save(buf, a, allow_pickle=False)
img.save(buf, format="PNG")
model.save(path)
text = json.dumps(record)
with open(path, "rb") as f:
    head = f.read(64)
import ray
ray.init(address=address, log_to_driver=False)
ray.init(num_cpus=2, include_dashboard=False, _node_ip_address="127.0.0.1")
"""
    assert scan_source(safe, "catgrasp_drake/example.py") == []
    assert scan_source("import subprocess\nsubprocess.run([sys.executable, '-m', 'x'])", "benchmarks/b.py") == []
    assert scan_source("import subprocess\nsubprocess.run(['ls'])", "catgrasp_drake/b.py") != []


# ----------------------------------------------------------------------------- by trying
def _listening_addresses(port: int) -> set[str]:
    """Local addresses (hex, as in /proc/net/tcp*) of the sockets listening on ``port``."""
    out = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            addr, p = fields[1].split(":")
            if int(p, 16) == port and fields[3] == "0A":  # 0A: LISTEN
                out.add(addr)
    return out


def test_meshcat_listens_on_localhost_only():
    from catgrasp_drake.viz.meshcat_tools import start_meshcat

    meshcat = start_meshcat()
    url = meshcat.web_url()
    assert re.match(r"http://(localhost|127\.0\.0\.1):\d+$", url), url
    if not Path("/proc/net/tcp").exists():
        pytest.skip("no /proc/net/tcp to read the bound address from")
    addrs = _listening_addresses(meshcat.port())
    loopback = {"0100007F", "00000000000000000000000001000000"}  # 127.0.0.1, ::1
    assert addrs and addrs <= loopback, addrs


def test_yaml_tags_never_run_code(tmp_path):
    from catgrasp_drake.grasping.constraints import load_constraint
    from catgrasp_drake.station.scenario import load_scenarios

    marker = tmp_path / "pwned"
    payload = f'!!python/object/apply:pathlib.Path.touch [!!python/object/apply:pathlib.Path ["{marker}"]]'
    path = tmp_path / "evil.yaml"
    path.write_text(f"drill_default:\n  object: {payload}\n")
    with pytest.raises(InputError) as e:
        load_scenarios(path)
    assert str(path) in str(e.value)  # (the message also carries PyYAML's own, multi-line, text)
    path.write_text(f"drill: {payload}\n")
    with pytest.raises((InputError, ModelFileError)):
        load_constraint("drill", path)
    assert not marker.exists()


class _Touch:
    """Unpickling this would create the marker file."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return (Path.touch, (Path(self.path),))


def test_model_and_cloud_files_are_never_unpickled(tmp_path):
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.data.cloud_io import read_point_cloud

    marker = tmp_path / "pwned"
    evil = np.empty(1, dtype=object)
    evil[0] = _Touch(marker)
    header = np.frombuffer(b'{"format": "catgrasp.category_model", "format_version": 1}', np.uint8)
    np.savez(tmp_path / "model.npz", __header__=header, evil=evil, allow_pickle=True)
    with pytest.raises(ModelFileError) as e:
        CategoryModel.load(tmp_path / "model.npz")
    assert str(tmp_path / "model.npz") in str(e.value) and "\n" not in str(e.value)
    np.save(tmp_path / "cloud.npy", evil, allow_pickle=True)
    with pytest.raises(ModelFileError):
        read_point_cloud(tmp_path / "cloud.npy")
    assert not marker.exists()


def test_save_arrays_refuses_object_arrays(tmp_path):
    from catgrasp_drake.core.fileio import save_arrays

    with pytest.raises(ValueError, match="dtype object"):
        save_arrays(tmp_path / "x.npz", {"a": np.array([{"x": 1}], dtype=object)}, kind="k", version=1)
    assert not (tmp_path / "x.npz").exists()
