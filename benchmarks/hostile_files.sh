#!/bin/bash
# Issue 19's file, path and command cases, one line each: exit code, stderr lines, the last stderr line.
#   benchmarks/hostile_files.sh SRC     (SRC: the src folder to run, e.g. $PWD/src)
# Needs the prepared ONNX model (pedenv models prepare) and ultralytics' bus.jpg (the ultralytics extra).
# Writes its data under $HOSTILE_TMP (default: a new folder from mktemp -d); docs/hostile_data.md holds the results.
set -u
SRC=$(realpath "$1"); ROOT=${HOSTILE_TMP:-$(mktemp -d)}; D=$ROOT/data; PY=${PYTHON:-python}
TESTS=$(dirname "$(realpath "$0")")/../tests
if [ ! -f $D/rec.mp4 ]; then
  mkdir -p $D
  PYTHONPATH=$SRC:$TESTS/recordings $PY - "$D" <<'PYEOF'
import importlib.util, struct, sys, zlib
from pathlib import Path
import cv2
from test_footage import _bus_recording
root = Path(sys.argv[1])
bus = Path(importlib.util.find_spec("ultralytics").submodule_search_locations[0]) / "assets" / "bus.jpg"
_bus_recording(root / "rec", bus, frames=3)
(root / "bus.jpg").write_bytes(bus.read_bytes())
def png(path, w, h):  # written row by row: 30000x30000 px in 2.6 MB
    def chunk(t, d): return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    c = zlib.compressobj(9); row = b"\0" * (3 * w + 1)
    data = b"".join(c.compress(row) for _ in range(h)) + c.flush()
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", data) + chunk(b"IEND", b""))
png(root / "huge.png", 30000, 30000)
png(root / "one.png", 1, 1)
w = cv2.VideoWriter(str(root / "rec.mp4"), cv2.VideoWriter.fourcc(*"mp4v"), 10, (640, 480))
for i in range(3):
    w.write(cv2.imread(str(root / "rec" / "images" / f"frame_{i:03d}.jpg")))
w.release()
PYEOF
fi
W=$(mktemp -d $ROOT/w.XXXX); cd $W
P() { PYTHONPATH=$SRC timeout ${T:-120} $PY -m pedenv "$@"; }
R="--images $D/rec/images --calibration $D/rec/calib.yaml --ego-poses $D/rec/poses.csv --pose-backend onnx --detection fast"
show() { last=$(grep -v '^\s*$' err | tail -1 | cut -c1-230); n=$(wc -l < err); echo "[$1] rc=$rc lines=$n :: $last ${2:-}"; }
cp $D/bus.jpg $'x\xff.jpg'
P detect $'x\xff.jpg' --output o1 --detection fast 2>err >/dev/null; rc=$?; show A-detect-nonutf8-file "json=$(ls o1/detections.json 2>/dev/null|wc -l)"
P detect $D/bus.jpg --output $'o\xff' --detection fast 2>err >/dev/null; rc=$?; show B-detect-nonutf8-output "json=$(ls $'o\xff'/detections.json 2>/dev/null|wc -l)"
P run $R --output $'r\xff' 2>err >/dev/null; rc=$?; show C-run-nonutf8-output "runjson=$(ls $'r\xff'/run.json 2>/dev/null|wc -l)"
cp $D/rec.mp4 $'v\xff.mp4'
P run --video $'v\xff.mp4' --calibration $D/rec/calib.yaml --ego-poses $D/rec/poses.csv --pose-backend onnx --detection fast --output o1v 2>err >/dev/null; rc=$?; show C2-run-nonutf8-video-input "frames=$($PY -c "import json;print(json.load(open('o1v/run.json'))['frames_done'])" 2>/dev/null)"
P run $R --video-out --output $'r2\xff' 2>err >/dev/null; rc=$?; show C3-run-video-out-nonutf8-output "overlay.mp4=$(ls $'r2\xff'/overlay.mp4 2>/dev/null|wc -l)"
( ulimit -v 6000000; P detect $D/huge.png --output o2 --detection fast 2>err >/dev/null ); rc=$?; show D-detect-30000px-png-ulimit6GB
T=25 P bench --frames 100000000 --no-pose 2>err >/dev/null; rc=$?; show E-bench-1e8-frames
mkdir rec && cp -r $D/rec/* rec/ && cp rec/poses.csv poses.bak
RR="--images rec/images --calibration rec/calib.yaml --ego-poses rec/poses.csv --pose-backend onnx --detection fast"
P run $RR --output o3 --mcap rec/poses.csv 2>err >/dev/null; rc=$?; show F1-mcap-onto-input "poses-intact=$(cmp -s rec/poses.csv poses.bak && echo yes || echo no)"
cp poses.bak rec/poses.csv
P run $RR --output o4 --rerun o4/environment.jsonl 2>err >/dev/null; rc=$?; show F2-rerun-onto-own-jsonl "jsonl-first-byte=$(head -c1 o4/environment.jsonl 2>/dev/null)"
echo old > old.rrd; P run $RR --output o5 --rerun old.rrd 2>err >/dev/null; rc=$?; show F3-rerun-existing-file "old.rrd=$(head -c3 old.rrd)"
mkdir adir; P run $RR --output o6 --rerun adir 2>err >/dev/null; rc=$?; show F4-rerun-folder
P run $RR --output o7 --mcap poses.bak/x.mcap 2>err >/dev/null; rc=$?; show F5-mcap-under-file
P run $RR --output o8 --rerun /proc/nope/x.rrd 2>err >/dev/null; rc=$?; show F6-rerun-unwritable
L=$(printf 'a%.0s' $(seq 300))
P run $RR --output $L 2>err >/dev/null; rc=$?; show G1-run-long-output
P detect $D/bus.jpg --output $L --detection fast 2>err >/dev/null; rc=$?; show G2-detect-long-output
P simulate --scenes 1 --output sim >/dev/null 2>&1
P evaluate --dataset synthetic --data-root sim --pose-backend ground-truth --output $L 2>err >/dev/null; rc=$?; show G3-evaluate-long-output
printf "name,images,calibration,ego_poses\n$L,rec/images,rec/calib.yaml,rec/poses.csv\n" > m.csv
P run --manifest m.csv --output o9 --pose-backend onnx --detection fast 2>err >/dev/null; rc=$?; show G4-manifest-long-name
cp rec/calib.yaml c1.yaml; echo "distortion: [0.1, 0, 0, 0, 0]" >> c1.yaml
P run $RR --calibration c1.yaml --output o10 2>err >/dev/null; rc=$?; show H1-calib-distortion
sed 's/^fx:/focal_lenght: 1\nfx:/' rec/calib.yaml > c2.yaml
P run $RR --calibration c2.yaml --output o11 2>err >/dev/null; rc=$?; show H2-calib-typo
sed 's/^fx:.*/fx: 1.0e+300/; s/^fy:.*/fy: 1.0e+300/' rec/calib.yaml > c3.yaml
P run $RR --calibration c3.yaml --output o12 2>err >/dev/null; rc=$?; show H3-calib-fx-1e300
printf "timestamp,x,y,z,qw,qx,qy,qz\n49.9,1e20,0,0,1,0,0,0\n50.7,1e20,0,0,1,0,0,0\n" > far.csv
P run $RR --ego-poses far.csv --output o13 2>err >/dev/null; rc=$?; show H4-ego-at-1e20
P detect $D/bus.jpg $D/one.png $D/rec/images/frame_001.jpg --output o14 --detection fast 2>err >/dev/null; rc=$?; show I-detect-good-1x1-good "images-in-json=$($PY -c "import json;print(len(json.load(open('o14/detections.json'))['images']))" 2>/dev/null)"
P run $RR --output o15 2>err >/dev/null
cp -r rec bad && $PY -c "open('bad/images/frame_000.jpg','wb').write(b'junk')"
P run --images bad/images --calibration rec/calib.yaml --ego-poses rec/poses.csv --pose-backend onnx --detection fast --output o15 --overwrite 2>err >/dev/null; rc=$?; show J-overwrite-bad-first-frame "old-overlays-kept=$(ls o15/overlays 2>/dev/null|wc -l)"
printf "name,images,calibration,ego_poses\nsummary.json,rec/images,rec/calib.yaml,rec/poses.csv\n" > m2.csv
P run --manifest m2.csv --output o16 --pose-backend onnx --detection fast 2>err >/dev/null; rc=$?; show K-manifest-name-summary.json "summary=$(test -f o16/summary.json && echo file || echo none)"
mkdir ':x:' && cp $D/bus.jpg ':x:/a.jpg'
P detect ':x:/a.jpg' ':x:/missing.jpg' --output o17 --detection fast 2>err >/dev/null; rc=$?; show N-emoji-path
rm -rf $W
