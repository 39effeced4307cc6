/* clvr_internal.h: the one way into a tracer's pipeline objects that is
 * left outside clvr.h, for the interactive viewer (host/app/viewer.c) only:
 * it draws the transfer function's colours and opacity curve, tone-maps the
 * running image itself and edits the renderer's settings per key press,
 * which the public API does not cover yet (see docs/library.md, "What the
 * API does not cover"). Not installed, not exported from libclvr.so; every
 * other part of the program uses clvr.h alone (tests/test_app_includes.sh). */
#ifndef CLVR_INTERNAL_H
#define CLVR_INTERNAL_H

#include "clvr.h"
#include "cl_context.h"
#include "preprocess.h"
#include "render.h"
#include "tf.h"

typedef struct clvr_tracer_parts {
    clvr_cl *cl;
    const clvr_clustered *clustered;
    clvr_renderer *renderer;
    const clvr_render_settings *rs;
    const clvr_camera *cam;
    clvr_tf *tf; /* the transfer function set by options; NULL after a table */
} clvr_tracer_parts;

/* The tracer's objects (owned by it, valid while it lives). Edits made
 * through them bypass the tracer's own bookkeeping (frames, the cached
 * table): the viewer is the tracer's last user. */
void clvr_tracer_parts_of(clvr_tracer *tr, clvr_tracer_parts *out);

#endif /* CLVR_INTERNAL_H */
