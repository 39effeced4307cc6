/* outline.h: context drawn over a rendered image: the edges of a box (the
 * mesh's bounds, a clip box) projected with the render camera (camera.h) as
 * thin antialiased lines, so that a wake is seen next to the body it comes
 * from. Works on the linear float image the renderer returns, before it is
 * written, so PNG, EXR and PFM get the same lines. */
#ifndef CLVR_OUTLINE_H
#define CLVR_OUTLINE_H

#include <stdint.h>

#include "clvr_shared.h"

/* Draws the 12 edges of the box [lo, hi] seen through cam into rgba
 * (cam->width * cam->height pixels, 4 floats each, rows top to bottom, as
 * clvr_renderer_read gives it). Each pixel's coverage c in [0, 1] is
 * 1 inside width_px / 2 of the projected edge, falling linearly to 0 one
 * pixel further (distance from the pixel centre to the segment), and the
 * line is composited over: rgb = rgb (1 - c) + colour c, alpha = alpha +
 * (1 - alpha) c (premultiplied, so a transparent background stays right).
 * Edges are cut at a near plane in front of the eye first, so a box around
 * the camera draws what is in front. colour is linear rgb. */
void clvr_outline_draw_box(float *rgba, const clvr_camera *cam, const float lo[3], const float hi[3],
                           const float colour[3], float width_px);

#endif /* CLVR_OUTLINE_H */
