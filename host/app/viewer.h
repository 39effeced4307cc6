/* viewer.h: the interactive viewer (`clvr --view`): a GLFW window that shows
 * the renderer's running mean image while it accumulates one sample per
 * pixel per frame, with an orbit camera, transfer-function editing, method
 * and light controls, image saving and a "print this view as a command line"
 * key. Every edit goes through the renderer's set_* calls, which restart the
 * accumulation (and, for the transfer function, recompute the majorants on
 * the device). The controls are listed in `clvr --help` (the H key prints
 * that section) and docs/viewer.md.
 *
 * Compiled only when CMake finds GLFW and OpenGL (CLVR_HAVE_VIEWER).
 *
 * Test hook: when the environment variable CLVR_VIEW_SCRIPT names a file,
 * the viewer executes its commands (one per line, '#' comments) between
 * frames, deterministically, as if they were typed:
 *   frames N              render and display N more frames
 *   key NAME [shift|ctrl|light]...   press a key (NAME: a letter, digit, LEFT,
 *                         RIGHT, UP, DOWN, PAGE_UP, PAGE_DOWN, HOME, ESCAPE,
 *                         [ ] { } + - =)
 *   drag left|middle|right DX DY [shift|ctrl|light]...  a mouse drag by (DX, DY)
 *                         window pixels ("light" = with L held)
 *   scroll DY             mouse wheel (DY > 0: zoom in)
 *   resize W H            resize the window (framebuffer) to W x H
 *   shot FILE             write what the window shows (glReadPixels) to FILE
 *                         with clvr_image_write (.png, .pfm, .exr)
 *   save FILE             write the accumulated image to FILE (a .png as the
 *                         P key writes it: exposure, tone curve)
 *   title                 print the window title (status line) to stdout
 *   run CMD...            run a shell command (e.g. xdotool sending real X
 *                         input), then handle the window events it caused
 *   quit                  close the viewer
 * At the end of the script the viewer stays open for the user unless the
 * script said quit. */
#ifndef CLVR_VIEWER_H
#define CLVR_VIEWER_H

#include "clvr.h"
#include "cli.h"

/* Largest accumulation the viewer runs to; after it, it idles until an
 * input event (the float sums lose precision beyond this anyway). */
#define CLVR_VIEWER_MAX_SPP 16384u

/* Checks that a window can be opened at all (a display is present and GLFW
 * initialises), so that `clvr --view` fails before the preprocessing.
 * Errors: CLVR_RESULT_ERR_NO_DEVICE ("no display", with the fix: run under a
 * display or render to a file with -o). */
clvr_result clvr_viewer_probe(clvr_message *err);

/* Runs the viewer until the window is closed (or Q / Escape, or the script's
 * quit). Takes what main has built:
 *   o       the parsed command line (initial window size o->width x
 *           o->height; the mesh path, colormap and other options for the
 *           printed command line; o->density the automatic density factor);
 *   tr      a tracer with camera and transfer function (set by options)
 *           set; the viewer changes its window size, method, shadows,
 *           light, camera and transfer function and leaves them in their
 *           last state;
 *   device  the device's name for the status line.
 * Errors: CLVR_RESULT_ERR_NO_DEVICE (no display / no OpenGL context), any renderer
 * error. Writes nothing to stdout except help, saved file names and the
 * printed command lines. */
clvr_result clvr_viewer_run(const clvr_options *o, clvr_tracer *tr, const char *device, clvr_message *err);

#endif /* CLVR_VIEWER_H */
