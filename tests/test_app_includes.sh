#!/bin/sh
# test_app_includes.sh SOURCE_DIR: the clvr program reaches libclvr through
# the public header alone. Every quoted #include of the program's sources
# (host/app) must name clvr.h or one of the program's own headers; system
# headers (<...>) are free. Checked: main, --stats, --info and the viewer;
# not the option parser and the series driver (cli.c, series.c), which use
# clvr's internal parsing helpers (docs/library.md). main.c may also hand
# over to the MPI mode's driver (mpi_main.h: two functions over the parsed
# options; that driver runs the renderer's phase kernels through
# host/api/clvr_internal.h, docs/mpi-compositing.md). Prints each offending
# line; exit 1 if there is one.
src=${1:?usage: test_app_includes.sh SOURCE_DIR}
app="$src/host/app"
allowed='clvr.h cli.h info.h series.h stats.h viewer.h mpi_main.h'
# The program's files that must use clvr.h alone.
files="main.c stats.c stats.h info.c info.h viewer.c viewer.h"
bad=0
checked=0
for f in $files; do
  [ -f "$app/$f" ] || { echo "test_app_includes: missing $app/$f"; exit 1; }
  checked=$((checked + 1))
  # Quoted includes only; comments are not code.
  for inc in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$app/$f"); do
    ok=0
    for a in $allowed; do [ "$inc" = "$a" ] && ok=1; done
    if [ $ok -eq 0 ]; then
      echo "host/app/$f includes \"$inc\": the program must use libclvr's public clvr.h (add what it needs there)"
      bad=1
    fi
  done
done
echo "test_app_includes: $checked files checked"
exit $bad
