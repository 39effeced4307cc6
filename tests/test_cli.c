/* Proves the command-line contract: defaults, every option's parsing, and a
 * clear usage error (naming the option) for each kind of bad value. */
#include "cli.h"
#include "image.h"
#include "clvr_shared.h"
#include "test_util.h"

/* The parser speaks libclvr's public clvr_result and clvr_message (the
 * program uses clvr.h alone); the same values as clvr_status and clvr_error
 * (clvr_api.c asserts it), converted for the checks below. */
static clvr_status parse(clvr_options *o, clvr_error *err, int n, const char **args)
{
    char *argv[64];
    if (n + 1 > 64) { fprintf(stderr, "test_cli: too many arguments\n"); exit(1); }
    argv[0] = (char *)"clvr";
    for (int i = 0; i < n; ++i) argv[i + 1] = (char *)args[i];
    clvr_message msg = {0};
    clvr_result r = clvr_cli_parse(n + 1, argv, o, &msg);
    err->status = (clvr_status)r;
    memcpy(err->msg, msg.text, sizeof err->msg);
    return (clvr_status)r;
}

#define PARSE(o, err, ...)                                                                  \
    parse(o, err, (int)(sizeof((const char *[]){__VA_ARGS__}) / sizeof(const char *)),      \
          (const char *[]){__VA_ARGS__})

/* The option named in a failure must appear in the message. */
static void expect_usage(const char *opt, const char *value)
{
    clvr_options o;
    clvr_error err = {0};
    const char *args[2] = {opt, value};
    clvr_status s = parse(&o, &err, value ? 2 : 1, args);
    TU_CHECK_STATUS(s, CLVR_ERR_USAGE, &err);
    if (!strstr(err.msg, opt)) {
        ++tu_fail_;
        fprintf(stderr, "message for %s %s does not name the option: %s\n", opt, value ? value : "", err.msg);
    }
}

int main(void)
{
    clvr_options o;
    clvr_error err = {0};

    TU_CHECK_STATUS(PARSE(&o, &err, "mesh.bin"), CLVR_OK, &err);
    TU_CHECK(o.mesh_path && strcmp(o.mesh_path, "mesh.bin") == 0);
    TU_CHECK(strcmp(o.output, "clvr.png") == 0);
    TU_CHECK_EQ_U64(o.width, 512);
    TU_CHECK_EQ_U64(o.spp, 16);
    TU_CHECK(o.method == CLVR_RENDER_DDA && o.shadows == 1 && o.leaf_size == 16);
    TU_CHECK(o.sampler == CLVR_SAMPLER_LD);

    TU_CHECK_STATUS(PARSE(&o, &err, "--device", "pocl", "--size", "640x480", "--spp", "7", "--seed", "99",
                          "-o", "x.exr", "--scalar", "p", "--stats-json", "s.json", "--method", "bins",
                          "--bins", "16", "--segments", "3", "--shadows", "off", "--range", "-1", "2.5",
                          "--camera", "1,2,3,0,0,0,0,0,1", "--light", "0,0,1", "--background", "1,1,1",
                          "--leaf-size", "8", "--macrocells", "32", "--fovy", "30", "--density", "2.5",
                          "--sampler", "independent"),
                    CLVR_OK, &err);
    TU_CHECK(strcmp(o.device, "pocl") == 0 && strcmp(o.output, "x.exr") == 0 && strcmp(o.scalar_name, "p") == 0);
    TU_CHECK_EQ_U64(o.width, 640);
    TU_CHECK_EQ_U64(o.height, 480);
    TU_CHECK_EQ_U64(o.spp, 7);
    TU_CHECK_EQ_U64(o.seed, 99);
    TU_CHECK(o.method == CLVR_RENDER_BINS && o.bins == 16 && o.segments == 3 && o.shadows == 0);
    TU_CHECK(o.sampler == CLVR_SAMPLER_INDEPENDENT);
    TU_CHECK(o.range_set && o.range_lo == -1.0f && o.range_hi == 2.5f);
    TU_CHECK(o.camera_set && o.camera[0] == 1.0f && o.camera[8] == 1.0f);
    TU_CHECK(o.leaf_size == 8 && o.macrocells == 32 && o.fovy == 30.0f && o.density == 2.5f);
    TU_CHECK(!o.density_auto && !o.opacity_ramp); /* --density D: that density, not the automatic one */
    TU_CHECK(o.light_dir[2] == 1.0f && o.background[0] == 1.0f);
    TU_CHECK_STATUS(PARSE(&o, &err, "--macrocells", "auto"), CLVR_OK, &err);
    TU_CHECK(o.macrocells == 0); /* the automatic grid */
    TU_CHECK_STATUS(PARSE(&o, &err, "m.bin"), CLVR_OK, &err);
    TU_CHECK(o.macrocells == 0); /* the default */
    TU_CHECK_STATUS(PARSE(&o, &err, "--macrocells", "0"), CLVR_ERR_USAGE, &err);

    /* The transfer function's defaults (issue 17): automatic opacity and
     * density; the old linear ramp by name. */
    TU_CHECK_STATUS(PARSE(&o, &err, "m.bin"), CLVR_OK, &err);
    TU_CHECK(o.density_auto && !o.opacity_ramp);
    TU_CHECK_STATUS(PARSE(&o, &err, "--opacity", "ramp", "--density", "auto"), CLVR_OK, &err);
    TU_CHECK(o.density_auto && o.opacity_ramp);
    TU_CHECK_STATUS(PARSE(&o, &err, "--opacity", "auto", "--density", "0.5"), CLVR_OK, &err);
    TU_CHECK(!o.density_auto && !o.opacity_ramp && o.density == 0.5f);
    expect_usage("--opacity", "linear");
    expect_usage("--density", "lots");
    TU_CHECK_STATUS(PARSE(&o, &err, "--density", "lots"), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "auto") != NULL); /* the fix names the other choice */

    /* Defaults of the view and display options: ParaView's 30 degrees, +y up,
     * the automatic framing unchanged, PNG through the aces curve, opaque. */
    TU_CHECK_STATUS(PARSE(&o, &err, "m.bin"), CLVR_OK, &err);
    TU_CHECK(o.fovy == 30.0f && o.up[0] == 0.0f && o.up[1] == 1.0f && o.up[2] == 0.0f);
    TU_CHECK(o.azimuth == 0.0f && o.elevation == 0.0f && o.zoom == 1.0f && o.orbit == 0 && !o.view_set);
    TU_CHECK(o.exposure == 0.0f && o.tonemap == CLVR_TONEMAP_ACES && !o.transparent);
    TU_CHECK_STATUS(PARSE(&o, &err, "--up", "-z", "--azimuth", "45", "--elevation", "-10", "--zoom", "2",
                          "--orbit", "36", "--exposure", "-1.5", "--tonemap", "none", "--background", "none"),
                    CLVR_OK, &err);
    TU_CHECK(o.up[2] == -1.0f && o.up[1] == 0.0f && o.view_set);
    TU_CHECK(o.azimuth == 45.0f && o.elevation == -10.0f && o.zoom == 2.0f && o.orbit == 36);
    TU_CHECK(o.exposure == -1.5f && o.tonemap == CLVR_TONEMAP_NONE && o.transparent);
    TU_CHECK(o.background[0] == 0.0f && o.background[1] == 0.0f && o.background[2] == 0.0f);
    TU_CHECK_STATUS(PARSE(&o, &err, "--tonemap", "filmic", "--background", "1,0,0"), CLVR_OK, &err);
    TU_CHECK(o.tonemap == CLVR_TONEMAP_FILMIC && !o.transparent && o.background[0] == 1.0f);
    /* The view options move the automatic framing: not with --camera. */
    TU_CHECK_STATUS(PARSE(&o, &err, "--camera", "1,2,3,0,0,0,0,1,0", "--azimuth", "10"), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "--camera") != NULL);
    TU_CHECK_STATUS(PARSE(&o, &err, "--camera", "1,2,3,0,0,0,0,1,0", "--orbit", "4"), CLVR_OK, &err);
    TU_CHECK_STATUS(PARSE(&o, &err, "--orbit", "4", "--view"), CLVR_ERR_USAGE, &err);
    expect_usage("--up", "w");
    expect_usage("--up", "xy");
    expect_usage("--zoom", "0");
    expect_usage("--orbit", "0");
    expect_usage("--exposure", "nan");
    expect_usage("--tonemap", "reinhard");
    expect_usage("--background", "transparent");

    /* Clipping and the outline: planes repeat up to CLVR_MAX_CLIP_PLANES. */
    TU_CHECK_STATUS(PARSE(&o, &err, "m.bin"), CLVR_OK, &err);
    TU_CHECK(o.num_clip_planes == 0 && !o.clip_box_set && !o.outline);
    TU_CHECK_STATUS(PARSE(&o, &err, "--clip", "1,0,0,0.5", "--clip", "0,-1,0,2", "--clip-box", "0,1,2,3,4,5",
                          "--outline"),
                    CLVR_OK, &err);
    TU_CHECK_EQ_U64(o.num_clip_planes, 2);
    TU_CHECK(o.clip_planes[0][0] == 1.0f && o.clip_planes[0][3] == 0.5f && o.clip_planes[1][1] == -1.0f &&
             o.clip_planes[1][3] == 2.0f);
    TU_CHECK(o.clip_box_set && o.clip_lo[0] == 0.0f && o.clip_lo[2] == 2.0f && o.clip_hi[0] == 3.0f &&
             o.clip_hi[2] == 5.0f);
    TU_CHECK(o.outline);
    TU_CHECK_STATUS(PARSE(&o, &err, "--clip", "1,0,0,0", "--clip", "1,0,0,0", "--clip", "1,0,0,0", "--clip",
                          "1,0,0,0", "--clip", "1,0,0,0", "--clip", "1,0,0,0", "--clip", "1,0,0,0"),
                    CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "more than 6") != NULL);
    expect_usage("--clip", "1,0,0");
    expect_usage("--clip", "0,0,0,1");
    expect_usage("--clip", "1,0,0,x");
    expect_usage("--clip-box", "0,0,0,1,1");
    expect_usage("--clip-box", "0,0,0,1,-1,1");
    expect_usage("--clip-box", "0,0,0,1,1,1,1");

    TU_CHECK_STATUS(PARSE(&o, &err, "--info", "--list-devices", "--help", "--stats"), CLVR_OK, &err);
    TU_CHECK(o.info && o.list_devices && o.help && o.stats && !o.mesh_path);

    expect_usage("--size", "0x10");
    expect_usage("--size", "12");
    expect_usage("--size", "100000x2");
    expect_usage("--spp", "0");
    expect_usage("--spp", "-3");
    expect_usage("--spp", "ten");
    expect_usage("--method", "raymarch");
    expect_usage("--bins", "33");
    expect_usage("--shadows", "maybe");
    expect_usage("--sampler", "sobol");
    expect_usage("--leaf-size", "3");
    expect_usage("--leaf-size", "2");
    expect_usage("--camera", "1,2,3");
    expect_usage("--camera", "1,2,3,4,5,6,7,8,nan");
    expect_usage("--light", "0,0,0");
    expect_usage("--fovy", "180");
    expect_usage("--density", "-1");
    expect_usage("--device", NULL);
    expect_usage("--bogus", NULL);
    TU_CHECK_STATUS(PARSE(&o, &err, "--range", "2", "1"), CLVR_ERR_USAGE, &err);
    /* --range auto-all takes one word; the next argument is the mesh. */
    TU_CHECK_STATUS(PARSE(&o, &err, "--range", "auto-all", "s.bin.series"), CLVR_OK, &err);
    TU_CHECK(o.range_auto_all && !o.range_set && o.mesh_path && strcmp(o.mesh_path, "s.bin.series") == 0);
    TU_CHECK_STATUS(PARSE(&o, &err, "--range", "1", "2", "--range", "auto-all"), CLVR_OK, &err);
    TU_CHECK(o.range_auto_all && !o.range_set);
    TU_CHECK_STATUS(PARSE(&o, &err, "a.bin", "b.bin"), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "b.bin") != NULL);
    return tu_finish("test_cli");
}
