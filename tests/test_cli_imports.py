"""The command line imports a workflow only when its command runs (issue 16, 17).

``--help``, ``--version`` and every subcommand's ``--help`` load none of heyoka, numpy, h5py,
matplotlib, mpmath, tqdm or sympy; ``info`` reads a double result, a sweep or a check file with
h5py and numpy but without heyoka; ``run`` loads nothing of the other commands' workflows.
Each case runs in a fresh interpreter, which reports what ``sys.modules`` holds afterwards.
(What these imports cost is measured in validation/users_cli.py, not here.)
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cayley_heyoka.cli import reference as reference_verb
from cayley_heyoka.cli import sweep as sweep_verb
from cayley_heyoka.workflows import plots, study
from cayley_heyoka.workflows import reference as reference_run

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(__file__).resolve().parent / "data" / "files"
HEAVY = ("heyoka", "numpy", "h5py", "matplotlib", "mpmath", "tqdm", "sympy", "dask")

# Runs main(argv) (a SystemExit from --help or --version included) and prints, as JSON, its
# exit code and which of the modules named after it were imported.
_RUNNER = """
import contextlib, io, json, sys
from cayley_heyoka.cli import main
argv, names = json.loads(sys.argv[1]), json.loads(sys.argv[2])
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
print(json.dumps({"code": code, "loaded": [n for n in names if n in sys.modules]}))
"""


def _loaded(argv: list[str], names: tuple[str, ...], cwd: Path = ROOT) -> tuple[int, list[str]]:
    proc = subprocess.run(
        [sys.executable, "-c", _RUNNER, json.dumps(argv), json.dumps(names)],
        capture_output=True,
        text=True,
        check=True,
        cwd=cwd,
        timeout=300,
    )
    out = json.loads(proc.stdout)
    return out["code"], out["loaded"]


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["--version"],
        *([verb, "--help"] for verb in ("run", "info", "check", "reference", "plot", "sweep")),
    ],
    ids=lambda argv: " ".join(argv),
)
def test_help_and_version_import_nothing_heavy(argv):
    code, loaded = _loaded(argv, HEAVY)
    assert code == 0
    assert loaded == []


@pytest.mark.parametrize("name", ["result_v1_double.h5", "sweep_v1.h5", "check_v1.h5"])
def test_info_reads_files_without_heyoka(name):
    code, loaded = _loaded(["info", str(DATA / name)], HEAVY)
    assert code == 0
    assert "h5py" in loaded  # it did read the file
    assert not {"heyoka", "matplotlib", "tqdm", "sympy", "dask"} & set(loaded)


def test_info_describes_variables_without_heyoka():
    """``info --variables`` asks the result's family what each variable is: the family's
    record and its descriptions load without the engine."""
    argv = ["info", "--variables", str(DATA / "result_v1_double.h5")]
    code, loaded = _loaded(argv, HEAVY)
    assert code == 0
    assert not {"heyoka", "matplotlib", "tqdm", "sympy", "dask"} & set(loaded)


def test_a_quad_result_is_read_with_heyoka():
    """The counterpart of the above: real128 numbers need heyoka's type (so the check above
    would see an import of heyoka if info made one)."""
    code, loaded = _loaded(["info", str(DATA / "result_v1_quad.h5")], ("heyoka",))
    assert (code, loaded) == (0, ["heyoka"])


def test_run_loads_no_other_commands_workflow(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [1, 0.1, 0.2]\n"
        "[output]\ntimes = [0, 1]\n"
    )
    others = tuple(
        f"cayley_heyoka.workflows.{m}"
        for m in ("plots", "sweep", "sweep_result", "reference", "checks")
    )
    code, loaded = _loaded(
        ["run", str(scene), "--no-progress"], ("heyoka", "matplotlib", "dask", *others)
    )
    assert (code, loaded) == (0, ["heyoka"])


def test_plot_kinds_come_from_the_families():
    """``plot --kind`` has no fixed choices: the drift, and each registered family's kinds."""
    assert plots.kinds() == ("drift", "polhode", "crossings", "orbit")


def test_the_parsers_choices_are_the_workflows():
    """The verb modules write their choices and defaults out (importing the workflow would
    load numpy); they must stay those of the workflow."""
    assert sweep_verb.BACKENDS == study.BACKENDS
    assert reference_verb.METHODS == reference_run.METHODS
    assert reference_verb.MAX_BITS == reference_run.MAX_BITS
    assert reference_verb.STRETCHES == reference_run.STRETCHES


@pytest.mark.parametrize("module", ["cayley_heyoka", "cayley_heyoka.cli"])
def test_python_dash_m_is_the_command(module):
    proc = subprocess.run(
        [sys.executable, "-m", module, "--version"], capture_output=True, text=True, cwd=ROOT
    )
    assert proc.returncode == 0
    assert proc.stdout.startswith("cayley-heyoka ") and "(heyoka " in proc.stdout
