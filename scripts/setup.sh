#!/usr/bin/env bash
# Create .venv (if missing) and install fsr with pinned dependencies. Idempotent.
#   bash scripts/setup.sh            # uses python3 (3.10-3.13, x86_64)
#   PYTHON=python3.12 bash scripts/setup.sh
set -euo pipefail
root="$(cd -P "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"  # physical: the same .venv path when called through a symlink
python="${PYTHON:-python3}"
venv="$root/.venv"
if [ ! -x "$venv/bin/python" ]; then
  "$python" -m venv "$venv"
fi
stamp="$venv/.fsr-installed"
want="$(cat "$root/requirements.txt" "$root"/ros_ws/src/*/setup.py "$root/scripts/setup.sh" | sha256sum | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$root/requirements.txt"
  # --use-pep517: PEP 660 editable installs (console scripts in .venv/bin) even though `wheel` is installed;
  # without it pip would fall back to `setup.py develop`, which puts the scripts in .venv/lib/<pkg> (setup.cfg)
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps --use-pep517 \
    -e "$root/ros_ws/src/fsr_sim" -e "$root/ros_ws/src/fsr_control" \
    -e "$root/ros_ws/src/fsr_estimation" -e "$root/ros_ws/src/fsr_bringup"
  echo "$want" > "$stamp"
fi
# tf2_msgs/msg/TFMessage (the type of /tf and /tf_static) built with the ROS build tools from the wheels (about 25 s,
# once), so the recorder publishes them over DDS; without cmake or a C compiler it says so and goes on.
bash "$root/scripts/build_tf2_msgs.sh" "$venv"
# Byte-compile fsr's sources: every node and fsr-fly starts faster (an environment with
# PYTHONDONTWRITEBYTECODE=1 would otherwise compile them at each start; a stale .pyc is simply recompiled).
"$venv/bin/python" -m compileall -q "$root/ros_ws/src" >/dev/null || true
# Compile the flight core once into numba's on-disk cache (a minute the first time, a second once cached),
# so that no flight and no node compiles anything.
"$venv/bin/fsr-compile"
echo "fsr environment ready: $venv"
