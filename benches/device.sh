#!/usr/bin/env bash
# The GPU check, one command for a machine with a GPU and no Rust toolchain or network:
#
#   bash benches/device.sh [--small]
#
# 1. installs the abi3 wheel from dist/ (`make wheel` here; Python >= 3.11) into a private
#    folder, without a network and without touching the machine's packages;
# 2. finds a Vulkan driver: where `ldconfig -p` has no libvulkan.so.1, it unpacks the loader
#    .deb files carried in .gl/ (fetched on a machine with apt: see benches/README.md), and
#    where no ICD is registered it points the loader at NVIDIA's (/usr/local/nvidia/...);
# 3. runs benches/gpu_check.py: every effect on the GPU against the CPU (parity, exit 1 when
#    one fails) and the 1080p rows timed on both, writing $OUT/gpu.md and $OUT/gpu.json
#    ($OUT defaults to benches/results/).
#
# --small checks at 96 x 54 and times at 160 x 90: the lavapipe run inside `make test`.
# Needs python3 with numpy, scipy, tqdm and scikit-image (PYTHON=... to choose another).
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-python3}"
OUT="${OUT:-benches/results}"
SMALL=()
[[ "${1:-}" == "--small" ]] && SMALL=(--small)

wheel=$(ls -t dist/skyfall-*-abi3-*.whl 2>/dev/null | head -n 1 || true)
if [[ -z "$wheel" ]]; then
  echo "device.sh: no abi3 wheel in dist/: run 'make wheel' on a machine with Rust first" >&2
  exit 2
fi
site=$(mktemp -d)/site
"$PY" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target "$site" "$wheel"
export PYTHONPATH="$site${PYTHONPATH:+:$PYTHONPATH}"

# (The loader list is read whole first: under pipefail, `ldconfig -p | grep -q` fails whenever
# grep's early exit cuts ldconfig off with SIGPIPE, which made this check flaky.)
loaders=$(ldconfig -p)
if ! grep -q 'libvulkan\.so\.1' <<<"$loaders"; then
  if compgen -G ".gl/*.deb" >/dev/null; then
    echo "device.sh: no Vulkan loader here: unpacking the carried .gl/*.deb"
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
  else
    echo "device.sh: no Vulkan loader (libvulkan.so.1) and no .gl/*.deb to bring one: see benches/README.md" >&2
    exit 2
  fi
fi
nv=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [[ -z "${VK_DRIVER_FILES:-}" && -f "$nv" ]] && ! compgen -G "/usr/share/vulkan/icd.d/nvidia*.json" >/dev/null; then
  export VK_DRIVER_FILES="$nv"
  export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"

echo "device.sh: $("$PY" --version), wheel $(basename "$wheel"), out $OUT"
exec "$PY" benches/gpu_check.py --out "$OUT" "${SMALL[@]}"
