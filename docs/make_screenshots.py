"""Make the README's pictures with pedenv's own commands, from the demo's synthetic scenes only.

    python docs/make_screenshots.py            # about 2-3 minutes on 2 cores

1. ``pedenv demo --rerun`` writes ``birds_eye.mp4`` (the crowd scene) and one Rerun
   recording per scene.
2. ``docs/birds_eye.gif``: every second frame of ``birds_eye.mp4``, 360x360, 5 frames/s shown
   at the recording's pace (OpenCV reads, Pillow writes; < 1.5 MB).
3. ``docs/rerun_viewer.png``: the crowd scene's recording (compacted with ``rerun rrd
   compact``, so that the viewer loads it in seconds) in the native Rerun viewer with the
   layout ``docs/rerun_layout.rbl`` (3D world beside the camera view; the layout this script
   writes), rendered by Mesa's software rasteriser under Xvfb and taken with the viewer's own
   ``--screenshot-to``; shrunk to 1600x900 and a 128-colour palette (< 300 KB).

Needs the viz extra (rerun-sdk), and for step 3 ``xvfb-run`` and Mesa's drivers:
``apt-get install -y xvfb xauth mesa-vulkan-drivers libgl1-mesa-dri``. The web viewer
(``rerun --serve-web`` in headless Chromium with ``--use-angle=swiftshader``) renders the
compacted recording as well; either viewer, rendering in software, loads only a few frames
a minute of a recording that is not compacted (pedenv logs each person as its own small
chunk), hence step 3's ``rerun rrd compact``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
SCENE = "crowd"  # the scene of the demo's bird's-eye video: the busiest


def run_demo(work: Path) -> Path:
    """``pedenv demo`` with a Rerun recording per scene; returns the demo's output folder."""
    out = work / "demo"
    subprocess.run([sys.executable, "-m", "pedenv", "demo", "--output", str(out), "--rerun", str(out / "demo.rrd")],
                   check=True, stdout=subprocess.DEVNULL)
    return out


def birds_eye_gif(video: Path, path: Path, *, every: int = 2, size: int = 360) -> Path:
    """Every ``every``-th frame of ``video`` as an animated GIF ``size`` pixels square."""
    import cv2
    from PIL import Image

    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS) or 10.0
    frames, index = [], 0
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        if index % every == 0:
            rgb = cv2.resize(bgr, (size, size), interpolation=cv2.INTER_AREA)[..., ::-1]
            frames.append(Image.fromarray(rgb).quantize(colors=64, method=Image.Quantize.MEDIANCUT))
        index += 1
    cap.release()
    if not frames:
        raise SystemExit(f"{video}: no frames")
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 * every / fps), loop=0,
                   optimize=True)
    return path


def rerun_layout(path: Path) -> Path:
    """The viewer layout: the 3D world beside the camera view, the side panels closed."""
    import rerun.blueprint as rrb

    blueprint = rrb.Blueprint(
        rrb.Horizontal(rrb.Spatial3DView(origin="world", name="world (ego, pedestrians, ground truth)"),
                       rrb.Spatial2DView(origin="world/ego/camera/image", name="camera: skeletons, boxes, ids"),
                       column_shares=[3, 2]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"))
    blueprint.save("pedenv", str(path))
    return path


def rerun_screenshot(recording: Path, layout: Path, path: Path, work: Path) -> Path:
    """The native viewer's own screenshot of ``recording``, shrunk and palettised."""
    from PIL import Image

    if shutil.which("xvfb-run") is None:
        raise SystemExit("xvfb-run is missing: apt-get install -y xvfb xauth mesa-vulkan-drivers libgl1-mesa-dri")
    compact = work / f"{recording.stem}-compact.rrd"
    rerun = [sys.executable, "-m", "rerun"]
    subprocess.run([*rerun, "rrd", "compact", str(recording), "-o", str(compact)], check=True,
                   stderr=subprocess.DEVNULL)
    raw = work / "viewer.png"
    env = {**os.environ, "XDG_RUNTIME_DIR": str(work)}
    # the viewer saves the picture, then exits with a panic of its own (rerun 0.23.1): judge by the file
    subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1600x900x24", *rerun, str(compact), str(layout),
                    "--port", "9877", "--window-size", "1600x900", "--screenshot-to", str(raw)],
                   env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=300)
    if not raw.is_file():
        raise SystemExit("the Rerun viewer made no screenshot (run the command above by hand to see why)")
    image = Image.open(raw).convert("RGB").resize((1600, 900), Image.Resampling.LANCZOS)
    image.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--skip-rerun", action="store_true", help="Only the bird's-eye GIF.")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="pedenv-shots-") as tmp:
        work = Path(tmp)
        demo = run_demo(work)
        for made in [birds_eye_gif(demo / "birds_eye.mp4", DOCS / "birds_eye.gif")] + (
                [] if args.skip_rerun else
                [rerun_screenshot(demo / f"demo-{SCENE}.rrd", rerun_layout(DOCS / "rerun_layout.rbl"),
                                  DOCS / "rerun_viewer.png", work)]):
            print(f"{made}: {made.stat().st_size / 1024:.0f} KB")


if __name__ == "__main__":
    main()
