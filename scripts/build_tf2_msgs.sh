#!/usr/bin/env bash
# Build tf2_msgs/msg/TFMessage's type support (interfaces/tf2_msgs) into a Python environment whose ROS wheels have
# no tf2_msgs, with the ROS build tools that come as wheels (ament_cmake, the rosidl generators: requirements.txt),
# CMake and a C/C++ compiler: the recorder then publishes /tf and /tf_static over DDS, for RViz or any ROS tool.
#   bash scripts/build_tf2_msgs.sh [VENV]        # default: .venv (scripts/setup.sh calls it)
# About 25 s on two cores, once: skipped while the sources and this script are unchanged and tf2_msgs loads. Without
# cmake, a C/C++ compiler or Python's headers it says what is missing and leaves the environment as it was (exit 0):
# /tf and /tf_static are then in recordings and on fsr-fly --live, not over DDS.
set -euo pipefail
root="$(cd -P "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$(cd -P "${1:-$root/.venv}" && pwd)"
python="$venv/bin/python"
src="$root/interfaces/tf2_msgs"
stamp="$venv/.fsr-tf2_msgs"
want="$(cat "$src/package.xml" "$src/CMakeLists.txt" "$src"/msg/*.msg "${BASH_SOURCE[0]}" | sha256sum | cut -d' ' -f1)"
loads='from tf2_msgs.msg import TFMessage; TFMessage.__class__.__import_type_support__()'
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ] && "$python" -c "$loads" 2>/dev/null; then
  exit 0
fi
skip() {
  echo "build_tf2_msgs: $1: tf2_msgs not built, /tf and /tf_static are not published over DDS (they are still in" \
    "recordings and on fsr-fly --live)" >&2
  exit 0
}
for tool in cmake cc c++; do
  command -v "$tool" >/dev/null || skip "no $tool on PATH"
done
build="$(mktemp -d)"
trap 'rm -rf "$build"' EXIT
log="$build/build.log"
# CMAKE_PREFIX_PATH: the wheels' CMake packages live under the environment's prefix (share/<pkg>/cmake).
if ! (cd "$build" && env CMAKE_PREFIX_PATH="$venv" AMENT_PREFIX_PATH="$venv" PATH="$venv/bin:$PATH" \
      cmake "$src" -DCMAKE_INSTALL_PREFIX="$venv" -DPython3_EXECUTABLE="$python" -DCMAKE_BUILD_TYPE=Release \
        -DBUILD_TESTING=OFF >"$log" 2>&1 \
      && cmake --build . --target install -j "$(nproc)" >>"$log" 2>&1); then
  tail -n 20 "$log" >&2
  skip "the build failed (above: the end of its log)"
fi
"$python" -c "$loads" || skip "the built tf2_msgs does not load"
echo "$want" > "$stamp"
echo "build_tf2_msgs: tf2_msgs/msg/TFMessage built into $venv"
