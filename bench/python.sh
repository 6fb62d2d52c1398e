#!/bin/sh
# bench/python.sh MECHC - the Python module's figures (bench/python.py) over
# the libmechc.so next to MECHC, with Debian's interpreter ($MECHC_PYTHON,
# default /usr/bin/python3); says why and does nothing where that
# interpreter, NumPy or cffi is missing.
#
#   sh bench/python.sh build/mechc          (part of `make bench`)
set -u
mechc=${1:-build/mechc}
py=${MECHC_PYTHON:-/usr/bin/python3}
so=$(cd "$(dirname "$mechc")" && pwd)/libmechc.so
if ! "$py" -c 'import numpy, cffi' 2> /dev/null; then
    echo "bench/python.sh: no NumPy or cffi for $py (sh .ci/deps python): not measured"
    exit 0
fi
if [ ! -f "$so" ]; then
    echo "bench/python.sh: no $so: not measured"
    exit 0
fi
PYTHONDONTWRITEBYTECODE=1 PYTHONPATH=python MECHC_LIBRARY=$so "$py" bench/python.py
