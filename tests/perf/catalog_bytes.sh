#!/bin/bash
# Are the catalog's datasets byte-identical at two revisions? Run explicitly (not part of the test suite):
#
#     bash tests/perf/catalog_bytes.sh OLD_REV NEW_REV [WORK_DIR]
#
# Installs simrig at each revision (from a clone of this repository, without dependencies, into its own
# folder put first on PYTHONPATH; the dependencies are this environment's), generates every catalog scenario
# with seed 0 at its own frame count, and compares every file of each dataset (manifest included) by SHA-256.
# Prints a table and writes it to reports/perf/catalog_bytes.md.
set -euo pipefail
old=$1; new=$2; work=${3:-$(mktemp -d)}
repo=$(cd "$(dirname "$0")/../.." && pwd)
export PYOPENGL_PLATFORM=egl
for rev in "$old" "$new"; do
  rm -rf "$work/$rev-src" "$work/$rev-site" "$work/$rev-data"
  git clone -q "$repo" "$work/$rev-src" && git -C "$work/$rev-src" checkout -q "$rev"
  python -m pip install -q --no-deps --target "$work/$rev-site" "$work/$rev-src" 2>&1 | grep -v WARNING || true
  for toml in "$work/$rev-src"/scenarios/*.toml; do
    name=$(basename "$toml" .toml)
    PYTHONPATH="$work/$rev-site" python -c "import sys; from simrig.cli import main; sys.exit(main(sys.argv[1:]))" \
      generate "$name" --seed 0 --out "$work/$rev-data/$name" --quiet > /dev/null
  done
done
digest() { (cd "$1" && find . -type f | sort | xargs sha256sum | sha256sum | cut -c1-16); }
report="$repo/reports/perf/catalog_bytes.md"
{
  echo "# The catalog's datasets at two revisions"
  echo
  echo "Produced by \`bash tests/perf/catalog_bytes.sh $old $new\`: every catalog scenario, seed 0, its own frame"
  echo "count; one SHA-256 over every file of the dataset (manifest included)."
  echo
  echo "| scenario | files | $old | $new | |"
  echo "|---|---:|---|---|---|"
  for folder in "$work/$old-data"/*; do
    name=$(basename "$folder")
    a=$(digest "$folder"); b=$(digest "$work/$new-data/$name")
    echo "| $name | $(find "$folder" -type f | wc -l) | $a | $b | $([ "$a" = "$b" ] && echo identical || echo DIFFERENT) |"
  done
} > "$report"
cat "$report"
