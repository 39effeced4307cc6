#!/bin/sh
# test_app_includes.sh SOURCE_DIR [CLVR_EXE [MPI_MODULE]]: the clvr program
# reaches libclvr through the public headers alone (issue 18: "the clvr
# program itself uses only this API, so the API cannot drift from what the
# program does").
#  1. Every quoted #include of every source of the program (host/app/*.c,
#     *.h) names clvr.h, clvr_mpi.h (the MPI module's entry) or one of the
#     program's own headers; system headers (<...>) are free.
#  2. With CLVR_EXE: the executable needs libclvr.so.1 (readelf NEEDED) and
#     defines no function of the pipeline or of the API itself (nm): it would
#     if it linked the static core again.
#  3. With MPI_MODULE (libclvr_mpi.so): the executable needs it too, and the
#     module exports exactly clvr_mpi_launched and clvr_mpi_main (its copy of
#     the pipeline stays hidden, so it cannot interpose libclvr's).
# Prints each offending line; exit 1 if there is one.
src=${1:?usage: test_app_includes.sh SOURCE_DIR [CLVR_EXE [MPI_MODULE]]}
exe=${2:-}
module=${3:-}
app="$src/host/app"
bad=0
checked=0
own=$(cd "$app" && ls *.h)
for path in "$app"/*.c "$app"/*.h; do
  f=${path##*/}
  checked=$((checked + 1))
  # Quoted includes only; comments are not code.
  for inc in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$path"); do
    ok=0
    for a in clvr.h clvr_mpi.h $own; do [ "$inc" = "$a" ] && ok=1; done
    if [ $ok -eq 0 ]; then
      echo "host/app/$f includes \"$inc\": the program must use libclvr's public clvr.h (add what it needs there)"
      bad=1
    fi
  done
done
[ $checked -ge 12 ] || { echo "test_app_includes: only $checked files in $app"; bad=1; }
echo "test_app_includes: $checked files of host/app checked"

if [ -n "$exe" ]; then
  needed=$(readelf -d "$exe" 2>/dev/null | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
  echo "$needed" | grep -qx 'libclvr\.so\.[0-9]*' ||
    { echo "$exe does not need libclvr.so (NEEDED: $(echo $needed)): the program must link the shared library"; bad=1; }
  syms=$(nm --defined-only "$exe" 2>/dev/null | awk '$2 ~ /^[TtDdBbRr]$/ {print $3}')
  # A stripped or unreadable executable proves nothing.
  echo "$syms" | grep -qx main || { echo "$exe: no symbol table (nm finds no main); cannot check it"; bad=1; }
  # Pipeline modules (preprocessing, trees, renderer, loaders, OpenCL
  # runtime, transfer functions, images) and the API's own functions.
  pipeline=$(echo "$syms" | grep -E '^(clvr_(preprocess|pp_|renderer_|render_settings|accel_|majorants|partition|mesh_|bin_writer|cl_|camera_|tf_|image_write|image_save|outline_|scene_default|series_read)|clvr_context_create$|clvr_tracer_render$|clvr_dataset_load)' | head -20)
  if [ -n "$pipeline" ]; then
    echo "$exe defines pipeline or API functions (it must get them from libclvr.so):"
    echo "$pipeline" | sed 's/^/  /'
    bad=1
  fi
  echo "test_app_includes: $exe: NEEDED $(echo $needed | tr '\n' ' '); $(echo "$syms" | wc -l) symbols defined, none of the pipeline's"
fi

if [ -n "$module" ]; then
  echo "$needed" | grep -qx 'libclvr_mpi\.so\.[0-9]*' ||
    { echo "$exe does not need libclvr_mpi.so: the MPI mode must come from the module"; bad=1; }
  exported=$(nm -D --defined-only "$module" 2>/dev/null | awk '$2 == "T" {print $3}' | sort | tr '\n' ' ')
  [ "$exported" = "clvr_mpi_launched clvr_mpi_main " ] ||
    { echo "$module exports '$exported'; expected exactly clvr_mpi_launched and clvr_mpi_main"; bad=1; }
  echo "test_app_includes: $module exports: $exported"
fi
exit $bad
