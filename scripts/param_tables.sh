#!/usr/bin/env bash
# Regenerates the parameter tables of the package READMEs (and docs/*.md pages): the lines between
#   <!-- BEGIN params <node> -->  and  <!-- END params <node> -->
# become `tactile params <node>` (from each node logic's default_parameters()). Run it after
# changing a parameter's default, range, unit or description; test_param_schema
# (tactile_cli, ParamTables.EveryDocumentTableIsTheGeneratedOne) fails until the tables match.
# Usage: scripts/param_tables.sh     (after a colcon build of tactile_cli)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tactile=""
for t in "$here/build/tactile_cli/tactile" "$here/install/tactile_cli/bin/tactile"; do
  if [[ -x "$t" ]]; then tactile="$t"; break; fi
done
if [[ -z "$tactile" ]]; then
  echo "param_tables: no tactile executable in build/tactile_cli/ or install/tactile_cli/bin/:" \
       "build it first (colcon build --packages-up-to tactile_cli)" >&2
  exit 1
fi
exec "$tactile" params --write-readme "$here/src"
