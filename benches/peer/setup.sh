#!/usr/bin/env bash
# Installs what the Mitsuba 3 peer benchmark needs. Idempotent: re-running only checks.
#   bash benches/peer/setup.sh
# Needs: python3 >= 3.11 with pip (tomllib), network access to PyPI and (for the LLVM
# variants) Debian's package archive. Not needed by `cargo test`.
set -euo pipefail

MITSUBA_VERSION="${MITSUBA_VERSION:-3.9.1}"   # brings drjit 1.5.0

py=python3
"$py" -c 'import sys; assert sys.version_info >= (3, 11), "python >= 3.11 needed (tomllib)"'

if "$py" -c "import mitsuba, numpy, sys; sys.exit(mitsuba.__version__ != '$MITSUBA_VERSION')" 2>/dev/null; then
    echo "mitsuba $MITSUBA_VERSION and numpy already installed"
else
    "$py" -m pip install --quiet "mitsuba==$MITSUBA_VERSION" numpy
fi

# Dr.Jit's LLVM backend (llvm_ad_* variants) loads libLLVM at run time.
llvm_lib=""
for cand in /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 /usr/lib/llvm-19/lib/libLLVM.so.1; do
    if [ -e "$cand" ]; then llvm_lib="$cand"; break; fi
done
if [ -z "$llvm_lib" ]; then
    if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
        llvm_lib=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
    else
        echo "warning: libLLVM 19 not found and cannot apt-get install libllvm19;" \
             "only the scalar variants will run" >&2
    fi
fi

if [ -n "$llvm_lib" ]; then
    export DRJIT_LIBLLVM_PATH="$llvm_lib"
    if DRJIT_LIBLLVM_PATH="$llvm_lib" "$py" -c "
import mitsuba as mi, drjit as dr
mi.set_variant('llvm_ad_spectral')
x = dr.llvm.Float([1.0, 2.0]) * 2.0
assert list(x) == [2.0, 4.0]
" ; then
        echo "llvm_ad_spectral works with DRJIT_LIBLLVM_PATH=$llvm_lib"
    else
        echo "warning: llvm_ad_spectral failed with $llvm_lib; only scalar variants will run" >&2
    fi
fi
"$py" -c "import mitsuba as mi; mi.set_variant('scalar_spectral'); print('scalar_spectral works, mitsuba', mi.__version__)"
