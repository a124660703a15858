"""The README's Python example runs as printed (headless: MPLBACKEND=Agg) and draws its plot."""
import os
import re
import subprocess
import sys

from conftest import REPO


def readme_python_block():
    with open(os.path.join(REPO, "README.md")) as f:
        text = f.read()
    section = text[text.index("## From Python"):]
    section = section[:section.index("\n## ", 1)]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1, "the README's Python section should have one example"
    return blocks[0]


def test_readme_example_runs_and_plots(tmp_path):
    script = tmp_path / "example.py"
    script.write_text(readme_python_block())
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.path.join(REPO, "python"))
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 0, res.stderr
    # 18 impacts: the exact solution's count in 10 s (test_walls.py checks them against it)
    m = re.search(r"impacts: (\d+), max \|H - H\(0\)\| = (\S+)", res.stdout)
    assert m, res.stdout
    assert int(m.group(1)) == 18
    assert float(m.group(2)) < 1e-8  # lobatto s = 4, hamiltonian condition: H kept to the scheme's error
    png = tmp_path / "walled_pendulum.png"
    assert png.exists()
    with open(png, "rb") as f:
        head = f.read(8)
    assert head == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000
