"""The paper's figures: drawn without pyplot, leaving the user's matplotlib as it was."""

import os
import subprocess
import sys
from pathlib import Path

import matplotlib.image
import numpy as np

from pedenv.visualize.plots import plot_error_by_distance

SRC = Path(__file__).resolve().parents[2] / "src"


def test_importing_pedenv_keeps_the_users_backend_and_skips_pyplot():
    code = ("import sys, matplotlib; matplotlib.use('svg'); "
            "import pedenv.visualize.plots, pedenv.apps.demo, pedenv.apps.compare, pedenv.cli.app; "
            "print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)")
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    env.pop("MPLBACKEND", None)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert done.stdout.split() == ["svg", "False"]


def test_error_by_distance_plot_leaves_pyplot_figures_alone(tmp_path):
    import matplotlib.pyplot as plt

    mine = plt.figure()
    before = plt.get_fignums()
    rows = [{"distance_m": float(d), "abs_error_m": 0.1 * d, "count": 10} for d in range(5, 40)]
    path = plot_error_by_distance({"paper": rows, "fused": rows[::2]}, tmp_path / "e.png", title="t")
    assert plt.get_fignums() == before
    plt.close(mine)
    image = matplotlib.image.imread(path)
    assert image.shape == (660, 990, 4)  # 9 x 6 inches at 110 dpi
    assert np.unique(image.reshape(-1, 4), axis=0).shape[0] > 10  # lines and text were drawn
