#!/usr/bin/env bash
# The papers' relative results (issue 22): the MLAB / AT papers' sweep
# (particles, hair, foliage at 1280x720 on iris-pro-5200: A-buffer, MLAB, HT,
# AT at k = 2..8) and the continuum paper's Table 3 sweep (foliage at
# 2560x1440 on titan-x-maxwell), their HTML reports, then results.md and
# frame-time-vs-k.png in this folder (make_page.py). The analysis is README.md.
#   reports/repro/papers/run.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/repro/papers] [JOBS=2]
# Run from the top of the repository with a Release build (scripts/build.sh).
# A sweep into WORKDIR runs only the points it does not hold yet (delete
# WORKDIR, or pass --force to oitsim sweep, after a model change).
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=${2:-out/repro/papers}
jobs=${3:-2}
here=$(cd "$(dirname "$0")" && pwd)
"$oitsim" sweep reports/sweep/papers-mlab.yaml --out "$work/mlab" --jobs "$jobs"
"$oitsim" report "$work/mlab"
"$oitsim" sweep reports/sweep/papers-continuum.yaml --out "$work/continuum" --jobs "$jobs"
"$oitsim" report "$work/continuum"
cp "$work/mlab/results.csv" "$here/mlab-results.csv"
cp "$work/continuum/results.csv" "$here/continuum-results.csv"
/usr/bin/python3 "$here/make_page.py" "$work/mlab" "$work/continuum" "$here"
