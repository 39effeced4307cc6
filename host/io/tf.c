/* tf.c: transfer functions: built-in colour maps, colour-space
 * interpolation as ParaView/VTK does it (vtkColorTransferFunction,
 * vtkPiecewiseFunction), baking into the table the kernels read, and the two
 * file formats (docs/transfer-function.md): a line-based text format and
 * ParaView's colour-map JSON export, read with a small strict JSON parser
 * (files are untrusted and fuzzed: every read is bounds-checked, nesting is
 * limited, every error names file:line:column and what was expected). */
#include "tf.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "image.h"
#include "json.h"

/* ------------------------------------------------------------ built-in maps */

/* ParaView's default "Cool to Warm" (Moreland 2009, "Diverging Color Maps
 * for Scientific Visualization"): its exact control points, interpolated in
 * Msh space ("Diverging"). */
static const float k_cool_warm[3][4] = {
    {0.0f, 0.23137254902f, 0.298039215686f, 0.752941176471f},
    {0.5f, 0.865f, 0.865f, 0.865f},
    {1.0f, 0.705882352941f, 0.0156862745098f, 0.149019607843f},
};

static const float k_grayscale[2][4] = {
    {0.0f, 0.0f, 0.0f, 0.0f},
    {1.0f, 1.0f, 1.0f, 1.0f},
};

/* matplotlib's viridis (lib/matplotlib/_cm_listed.py, CC0): every 4th of its
 * 256 entries and the last, as {entry index, r, g, b}; x = index / 255.
 * Linear interpolation between them stays within 0.002 of every entry. */
static const float k_viridis[65][4] = {
    {0.0f, 0.267004f, 0.004874f, 0.329415f},
    {4.0f, 0.272594f, 0.025563f, 0.353093f},
    {8.0f, 0.277018f, 0.050344f, 0.375715f},
    {12.0f, 0.280267f, 0.073417f, 0.397163f},
    {16.0f, 0.282327f, 0.094955f, 0.417331f},
    {20.0f, 0.283197f, 0.115680f, 0.436115f},
    {24.0f, 0.282884f, 0.135920f, 0.453427f},
    {28.0f, 0.281412f, 0.155834f, 0.469201f},
    {32.0f, 0.278826f, 0.175490f, 0.483397f},
    {36.0f, 0.275191f, 0.194905f, 0.496005f},
    {40.0f, 0.270595f, 0.214069f, 0.507052f},
    {44.0f, 0.265145f, 0.232956f, 0.516599f},
    {48.0f, 0.258965f, 0.251537f, 0.524736f},
    {52.0f, 0.252194f, 0.269783f, 0.531579f},
    {56.0f, 0.244972f, 0.287675f, 0.537260f},
    {60.0f, 0.237441f, 0.305202f, 0.541921f},
    {64.0f, 0.229739f, 0.322361f, 0.545706f},
    {68.0f, 0.221989f, 0.339161f, 0.548752f},
    {72.0f, 0.214298f, 0.355619f, 0.551184f},
    {76.0f, 0.206756f, 0.371758f, 0.553117f},
    {80.0f, 0.199430f, 0.387607f, 0.554642f},
    {84.0f, 0.192357f, 0.403199f, 0.555836f},
    {88.0f, 0.185556f, 0.418570f, 0.556753f},
    {92.0f, 0.179019f, 0.433756f, 0.557430f},
    {96.0f, 0.172719f, 0.448791f, 0.557885f},
    {100.0f, 0.166617f, 0.463708f, 0.558119f},
    {104.0f, 0.160665f, 0.478540f, 0.558115f},
    {108.0f, 0.154815f, 0.493313f, 0.557840f},
    {112.0f, 0.149039f, 0.508051f, 0.557250f},
    {116.0f, 0.143343f, 0.522773f, 0.556295f},
    {120.0f, 0.137770f, 0.537492f, 0.554906f},
    {124.0f, 0.132444f, 0.552216f, 0.553018f},
    {128.0f, 0.127568f, 0.566949f, 0.550556f},
    {132.0f, 0.123463f, 0.581687f, 0.547445f},
    {136.0f, 0.120565f, 0.596422f, 0.543611f},
    {140.0f, 0.119423f, 0.611141f, 0.538982f},
    {144.0f, 0.120638f, 0.625828f, 0.533488f},
    {148.0f, 0.124780f, 0.640461f, 0.527068f},
    {152.0f, 0.132268f, 0.655014f, 0.519661f},
    {156.0f, 0.143303f, 0.669459f, 0.511215f},
    {160.0f, 0.157851f, 0.683765f, 0.501686f},
    {164.0f, 0.175707f, 0.697900f, 0.491033f},
    {168.0f, 0.196571f, 0.711827f, 0.479221f},
    {172.0f, 0.220124f, 0.725509f, 0.466226f},
    {176.0f, 0.246070f, 0.738910f, 0.452024f},
    {180.0f, 0.274149f, 0.751988f, 0.436601f},
    {184.0f, 0.304148f, 0.764704f, 0.419943f},
    {188.0f, 0.335885f, 0.777018f, 0.402049f},
    {192.0f, 0.369214f, 0.788888f, 0.382914f},
    {196.0f, 0.404001f, 0.800275f, 0.362552f},
    {200.0f, 0.440137f, 0.811138f, 0.340967f},
    {204.0f, 0.477504f, 0.821444f, 0.318195f},
    {208.0f, 0.515992f, 0.831158f, 0.294279f},
    {212.0f, 0.555484f, 0.840254f, 0.269281f},
    {216.0f, 0.595839f, 0.848717f, 0.243329f},
    {220.0f, 0.636902f, 0.856542f, 0.216620f},
    {224.0f, 0.678489f, 0.863742f, 0.189503f},
    {228.0f, 0.720391f, 0.870350f, 0.162603f},
    {232.0f, 0.762373f, 0.876424f, 0.137064f},
    {236.0f, 0.804182f, 0.882046f, 0.114965f},
    {240.0f, 0.845561f, 0.887322f, 0.099702f},
    {244.0f, 0.886271f, 0.892374f, 0.095374f},
    {248.0f, 0.926106f, 0.897330f, 0.104071f},
    {252.0f, 0.964894f, 0.902323f, 0.123941f},
    {255.0f, 0.993248f, 0.906157f, 0.143936f},
};
/* matplotlib's inferno (lib/matplotlib/_cm_listed.py, CC0): every 4th of its
 * 256 entries and the last, as {entry index, r, g, b}; x = index / 255.
 * Linear interpolation between them stays within 0.002 of every entry. */
static const float k_inferno[65][4] = {
    {0.0f, 0.001462f, 0.000466f, 0.013866f},
    {4.0f, 0.006006f, 0.004692f, 0.038558f},
    {8.0f, 0.013995f, 0.011225f, 0.071862f},
    {12.0f, 0.025793f, 0.019331f, 0.105930f},
    {16.0f, 0.042253f, 0.028139f, 0.141141f},
    {20.0f, 0.061340f, 0.036590f, 0.177642f},
    {24.0f, 0.081962f, 0.043328f, 0.215289f},
    {28.0f, 0.104551f, 0.047008f, 0.253430f},
    {32.0f, 0.129285f, 0.047293f, 0.290788f},
    {36.0f, 0.155850f, 0.044559f, 0.325338f},
    {40.0f, 0.183429f, 0.040329f, 0.354971f},
    {44.0f, 0.211095f, 0.037030f, 0.378563f},
    {48.0f, 0.238273f, 0.036621f, 0.396353f},
    {52.0f, 0.264810f, 0.039647f, 0.409345f},
    {56.0f, 0.290763f, 0.045644f, 0.418637f},
    {60.0f, 0.316282f, 0.053490f, 0.425116f},
    {64.0f, 0.341500f, 0.062325f, 0.429425f},
    {68.0f, 0.366529f, 0.071579f, 0.431994f},
    {72.0f, 0.391453f, 0.080927f, 0.433109f},
    {76.0f, 0.416331f, 0.090203f, 0.432943f},
    {80.0f, 0.441207f, 0.099338f, 0.431594f},
    {84.0f, 0.466100f, 0.108322f, 0.429125f},
    {88.0f, 0.491022f, 0.117179f, 0.425552f},
    {92.0f, 0.515967f, 0.125960f, 0.420887f},
    {96.0f, 0.540920f, 0.134729f, 0.415123f},
    {100.0f, 0.565854f, 0.143567f, 0.408258f},
    {104.0f, 0.590734f, 0.152563f, 0.400290f},
    {108.0f, 0.615513f, 0.161817f, 0.391219f},
    {112.0f, 0.640135f, 0.171438f, 0.381065f},
    {116.0f, 0.664540f, 0.181539f, 0.369846f},
    {120.0f, 0.688653f, 0.192239f, 0.357603f},
    {124.0f, 0.712396f, 0.203656f, 0.344383f},
    {128.0f, 0.735683f, 0.215906f, 0.330245f},
    {132.0f, 0.758422f, 0.229097f, 0.315266f},
    {136.0f, 0.780517f, 0.243327f, 0.299523f},
    {140.0f, 0.801871f, 0.258674f, 0.283099f},
    {144.0f, 0.822386f, 0.275197f, 0.266085f},
    {148.0f, 0.841969f, 0.292933f, 0.248564f},
    {152.0f, 0.860533f, 0.311892f, 0.230606f},
    {156.0f, 0.878001f, 0.332060f, 0.212268f},
    {160.0f, 0.894305f, 0.353399f, 0.193584f},
    {164.0f, 0.909390f, 0.375856f, 0.174563f},
    {168.0f, 0.923215f, 0.399359f, 0.155193f},
    {172.0f, 0.935747f, 0.423831f, 0.135440f},
    {176.0f, 0.946965f, 0.449191f, 0.115272f},
    {180.0f, 0.956852f, 0.475356f, 0.094695f},
    {184.0f, 0.965397f, 0.502249f, 0.073859f},
    {188.0f, 0.972590f, 0.529798f, 0.053324f},
    {192.0f, 0.978422f, 0.557937f, 0.034931f},
    {196.0f, 0.982881f, 0.586606f, 0.024661f},
    {200.0f, 0.985952f, 0.615750f, 0.025592f},
    {204.0f, 0.987622f, 0.645320f, 0.039886f},
    {208.0f, 0.987874f, 0.675267f, 0.065257f},
    {212.0f, 0.986694f, 0.705540f, 0.095694f},
    {216.0f, 0.984075f, 0.736087f, 0.129527f},
    {220.0f, 0.980032f, 0.766837f, 0.166353f},
    {224.0f, 0.974638f, 0.797692f, 0.206332f},
    {228.0f, 0.968041f, 0.828515f, 0.249972f},
    {232.0f, 0.960626f, 0.859069f, 0.298010f},
    {236.0f, 0.953215f, 0.888942f, 0.351369f},
    {240.0f, 0.947594f, 0.917399f, 0.410665f},
    {244.0f, 0.946903f, 0.943348f, 0.474970f},
    {248.0f, 0.954529f, 0.965896f, 0.540361f},
    {252.0f, 0.971162f, 0.985282f, 0.602154f},
    {255.0f, 0.988362f, 0.998364f, 0.644924f},
};
/* matplotlib's jet (lib/matplotlib/_cm.py _jet_data) as the union of the
 * three channels' breakpoints, so RGB interpolation reproduces it (to float
 * precision). */
static const float k_jet[12][4] = {
    {0.0f, 0.0f, 0.0f, 0.5f},
    {0.11f, 0.0f, 0.0f, 1.0f},
    {0.125f, 0.0f, 0.0f, 1.0f},
    {0.34f, 0.0f, 0.86f, 1.0f},
    {0.35f, 0.0f, 0.9f, 0.9677419f},
    {0.375f, 0.08064516f, 1.0f, 0.8870968f},
    {0.64f, 0.9354839f, 1.0f, 0.03225806f},
    {0.65f, 0.9677419f, 0.962963f, 0.0f},
    {0.66f, 1.0f, 0.9259259f, 0.0f},
    {0.89f, 1.0f, 0.07407407f, 0.0f},
    {0.91f, 0.9090909f, 0.0f, 0.0f},
    {1.0f, 0.5f, 0.0f, 0.0f},
};

typedef struct builtin_map {
    const char *name;
    uint32_t space;
    const float (*points)[4];
    uint32_t count;
    float x_scale; /* the first column times this is x */
} builtin_map;

static const builtin_map k_maps[] = {
    {"cool-warm", CLVR_TF_SPACE_DIVERGING, k_cool_warm, 3, 1.0f},
    {"viridis", CLVR_TF_SPACE_RGB, k_viridis, sizeof k_viridis / sizeof k_viridis[0], 1.0f / 255.0f},
    {"inferno", CLVR_TF_SPACE_RGB, k_inferno, sizeof k_inferno / sizeof k_inferno[0], 1.0f / 255.0f},
    {"grayscale", CLVR_TF_SPACE_RGB, k_grayscale, 2, 1.0f},
    {"jet", CLVR_TF_SPACE_RGB, k_jet, sizeof k_jet / sizeof k_jet[0], 1.0f},
};
#define NUM_MAPS (sizeof k_maps / sizeof k_maps[0])

const char *clvr_tf_colormap_names(void) { return "cool-warm, viridis, inferno, grayscale, jet"; }

static const builtin_map *find_map(const char *name)
{
    for (size_t i = 0; i < NUM_MAPS; ++i)
        if (!strcasecmp(name, k_maps[i].name)) return &k_maps[i];
    /* ParaView's and matplotlib's spellings. */
    if (!strcasecmp(name, "coolwarm") || !strcasecmp(name, "cool to warm") || !strcasecmp(name, "cool_warm"))
        return &k_maps[0];
    if (!strcasecmp(name, "grey") || !strcasecmp(name, "gray") || !strcasecmp(name, "greyscale") ||
        !strcasecmp(name, "grayscale"))
        return &k_maps[3];
    return NULL;
}

/* ------------------------------------------------------------ colour spaces
 * As vtkMath / vtkColorTransferFunction: sRGB-encoded rgb <-> XYZ (D65) <->
 * CIELAB (white 0.9505, 1, 1.089) <-> Msh (Moreland). */

static double srgb_dec(double c) { return c > 0.04045 ? pow((c + 0.055) / 1.055, 2.4) : c / 12.92; }
static double srgb_enc(double c) { return c > 0.0031308 ? 1.055 * pow(c, 1.0 / 2.4) - 0.055 : 12.92 * c; }

static void rgb_to_lab(const double rgb[3], double lab[3])
{
    double r = srgb_dec(rgb[0]), g = srgb_dec(rgb[1]), b = srgb_dec(rgb[2]);
    double xyz[3] = {r * 0.4124 + g * 0.3576 + b * 0.1805, r * 0.2126 + g * 0.7152 + b * 0.0722,
                     r * 0.0193 + g * 0.1192 + b * 0.9505};
    const double ref[3] = {0.9505, 1.000, 1.089};
    double f[3];
    for (int k = 0; k < 3; ++k) {
        double t = xyz[k] / ref[k];
        f[k] = t > 0.008856 ? cbrt(t) : 7.787 * t + 16.0 / 116.0;
    }
    lab[0] = 116.0 * f[1] - 16.0;
    lab[1] = 500.0 * (f[0] - f[1]);
    lab[2] = 200.0 * (f[1] - f[2]);
}

static void lab_to_rgb(const double lab[3], double rgb[3])
{
    const double ref[3] = {0.9505, 1.000, 1.089};
    double fy = (lab[0] + 16.0) / 116.0;
    double f[3] = {lab[1] / 500.0 + fy, fy, fy - lab[2] / 200.0}, xyz[3];
    for (int k = 0; k < 3; ++k) {
        double c = f[k] * f[k] * f[k];
        xyz[k] = ref[k] * (c > 0.008856 ? c : (f[k] - 16.0 / 116.0) / 7.787);
    }
    double r = xyz[0] * 3.2406 + xyz[1] * -1.5372 + xyz[2] * -0.4986;
    double g = xyz[0] * -0.9689 + xyz[1] * 1.8758 + xyz[2] * 0.0415;
    double b = xyz[0] * 0.0557 + xyz[1] * -0.2040 + xyz[2] * 1.0570;
    rgb[0] = srgb_enc(r);
    rgb[1] = srgb_enc(g);
    rgb[2] = srgb_enc(b);
    /* VTK's gamut clip: scale down if above 1, then clamp at 0. */
    double m = fmax(rgb[0], fmax(rgb[1], rgb[2]));
    for (int k = 0; k < 3; ++k) {
        if (m > 1.0) rgb[k] /= m;
        if (rgb[k] < 0.0) rgb[k] = 0.0;
    }
}

static void rgb_to_msh(const double rgb[3], double msh[3])
{
    double lab[3];
    rgb_to_lab(rgb, lab);
    double m = sqrt(lab[0] * lab[0] + lab[1] * lab[1] + lab[2] * lab[2]);
    double s = m > 0.001 ? acos(lab[0] / m) : 0.0;
    double h = s > 0.001 ? atan2(lab[2], lab[1]) : 0.0;
    msh[0] = m;
    msh[1] = s;
    msh[2] = h;
}

static void msh_to_rgb(const double msh[3], double rgb[3])
{
    double lab[3] = {msh[0] * cos(msh[1]), msh[0] * sin(msh[1]) * cos(msh[2]), msh[0] * sin(msh[1]) * sin(msh[2])};
    lab_to_rgb(lab, rgb);
}

static double angle_diff(double a, double b)
{
    double d = fabs(a - b);
    while (d >= 2.0 * M_PI) d -= 2.0 * M_PI;
    return d > M_PI ? 2.0 * M_PI - d : d;
}

/* Hue for an unsaturated colour next to a saturated one (Moreland). */
static double adjust_hue(const double msh[3], double unsat_m)
{
    if (msh[0] >= unsat_m - 0.1) return msh[2];
    double spin = msh[1] * sqrt(unsat_m * unsat_m - msh[0] * msh[0]) / (msh[0] * sin(msh[1]));
    return msh[2] > -0.3 * M_PI ? msh[2] + spin : msh[2] - spin;
}

static void interp_diverging(double s, const double c1[3], const double c2[3], double out[3])
{
    double m1[3], m2[3];
    rgb_to_msh(c1, m1);
    rgb_to_msh(c2, m2);
    /* Two distinct saturated ends: white in the middle. */
    if (m1[1] > 0.05 && m2[1] > 0.05 && angle_diff(m1[2], m2[2]) > 0.33 * M_PI) {
        double mid = fmax(88.0, fmax(m1[0], m2[0]));
        if (s < 0.5) { m2[0] = mid; m2[1] = 0.0; m2[2] = 0.0; s = 2.0 * s; }
        else { m1[0] = mid; m1[1] = 0.0; m1[2] = 0.0; s = 2.0 * s - 1.0; }
    }
    if (m1[1] < 0.05 && m2[1] > 0.05) m1[2] = adjust_hue(m2, m1[0]);
    else if (m2[1] < 0.05 && m1[1] > 0.05) m2[2] = adjust_hue(m1, m2[0]);
    double m[3];
    for (int k = 0; k < 3; ++k) m[k] = (1.0 - s) * m1[k] + s * m2[k];
    msh_to_rgb(m, out);
}

static void rgb_to_hsv(const double c[3], double hsv[3])
{
    double mx = fmax(c[0], fmax(c[1], c[2])), mn = fmin(c[0], fmin(c[1], c[2]));
    double d = mx - mn, h = 0.0;
    if (d > 0.0) {
        if (mx == c[0]) h = (c[1] - c[2]) / d;
        else if (mx == c[1]) h = 2.0 + (c[2] - c[0]) / d;
        else h = 4.0 + (c[0] - c[1]) / d;
        h /= 6.0;
        if (h < 0.0) h += 1.0;
    }
    hsv[0] = h;
    hsv[1] = mx > 0.0 ? d / mx : 0.0;
    hsv[2] = mx;
}

static void hsv_to_rgb(const double hsv[3], double c[3])
{
    double h = hsv[0] * 6.0, s = hsv[1], v = hsv[2];
    int i = (int)floor(h);
    double f = h - i, p = v * (1.0 - s), q = v * (1.0 - s * f), t = v * (1.0 - s * (1.0 - f));
    switch (((i % 6) + 6) % 6) {
    case 0: c[0] = v; c[1] = t; c[2] = p; break;
    case 1: c[0] = q; c[1] = v; c[2] = p; break;
    case 2: c[0] = p; c[1] = v; c[2] = t; break;
    case 3: c[0] = p; c[1] = q; c[2] = v; break;
    case 4: c[0] = t; c[1] = p; c[2] = v; break;
    default: c[0] = v; c[1] = p; c[2] = q; break;
    }
}

static void interp_color(uint32_t space, double s, const double a[3], const double b[3], double out[3])
{
    double u[3], v[3], w[3];
    switch (space) {
    case CLVR_TF_SPACE_LAB:
        rgb_to_lab(a, u);
        rgb_to_lab(b, v);
        for (int k = 0; k < 3; ++k) w[k] = (1.0 - s) * u[k] + s * v[k];
        lab_to_rgb(w, out);
        break;
    case CLVR_TF_SPACE_DIVERGING: interp_diverging(s, a, b, out); break;
    case CLVR_TF_SPACE_HSV:
        rgb_to_hsv(a, u);
        rgb_to_hsv(b, v);
        /* The shorter way round the hue circle (VTK's HSVWrap). */
        if (u[0] - v[0] > 0.5) u[0] -= 1.0;
        else if (v[0] - u[0] > 0.5) v[0] -= 1.0;
        for (int k = 0; k < 3; ++k) w[k] = (1.0 - s) * u[k] + s * v[k];
        if (w[0] < 0.0) w[0] += 1.0;
        hsv_to_rgb(w, out);
        break;
    case CLVR_TF_SPACE_STEP:
        for (int k = 0; k < 3; ++k) out[k] = a[k];
        break;
    default:
        for (int k = 0; k < 3; ++k) out[k] = a[k] + s * (b[k] - a[k]);
        break;
    }
}

/* Segment of x in points (stride 4, x first, non-decreasing): returns k with
 * pts[k].x <= x < pts[k+1].x, or -1 / n-1 when x is before / after them. At
 * a repeated position the later point wins (a step). */
static long find_segment(const float *pts, uint32_t n, float x)
{
    if (n == 0 || !(x >= pts[0])) return -1;
    if (x >= pts[4 * (size_t)(n - 1)]) return (long)n - 1;
    uint32_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (pts[4 * (size_t)mid] <= x) lo = mid;
        else hi = mid;
    }
    return (long)lo;
}

static float clamp01(float x) { return x > 0.0f ? (x < 1.0f ? x : 1.0f) : 0.0f; /* NaN -> 0 */ }

void clvr_tf_color(const clvr_tf *tf, float x, float srgb[3])
{
    x = clamp01(x);
    if (!tf->num_colors) { srgb[0] = srgb[1] = srgb[2] = 0.0f; return; } /* not initialised */
    long k = find_segment(tf->colors, tf->num_colors, x);
    if (k < 0 || k >= (long)tf->num_colors - 1) {
        const float *p = tf->colors + 4 * (size_t)(k < 0 ? 0 : k);
        for (int c = 0; c < 3; ++c) srgb[c] = p[1 + c];
        return;
    }
    const float *p = tf->colors + 4 * (size_t)k, *q = p + 4;
    double s = ((double)x - p[0]) / ((double)q[0] - p[0]);
    double a[3] = {p[1], p[2], p[3]}, b[3] = {q[1], q[2], q[3]}, o[3];
    /* On a control point its colour exactly (no colour-space round trip). */
    if (s <= 0.0) for (int c = 0; c < 3; ++c) o[c] = a[c];
    else interp_color(tf->space, s, a, b, o);
    for (int c = 0; c < 3; ++c) srgb[c] = clamp01((float)o[c]);
}

/* vtkPiecewiseFunction's value between (x1, y1) and (x2, y2) at fraction s,
 * with the segment's midpoint and sharpness. */
static double opacity_segment(double s, double y1, double y2, double midpoint, double sharpness)
{
    if (s < midpoint) s = 0.5 * s / midpoint;
    else s = midpoint < 1.0 ? 0.5 + 0.5 * (s - midpoint) / (1.0 - midpoint) : 0.5;
    if (sharpness > 0.99) return s < 0.5 ? y1 : y2;
    if (sharpness < 0.01) return (1.0 - s) * y1 + s * y2;
    if (s < 0.5) s = 0.5 * pow(s * 2.0, 1.0 + 10.0 * sharpness);
    else if (s > 0.5) s = 1.0 - 0.5 * pow((1.0 - s) * 2.0, 1.0 + 10.0 * sharpness);
    double ss = s * s, sss = ss * s;
    double h1 = 2.0 * sss - 3.0 * ss + 1.0, h2 = -2.0 * sss + 3.0 * ss, h3 = sss - 2.0 * ss + s, h4 = sss - ss;
    double t = (1.0 - sharpness) * (y2 - y1);
    double v = h1 * y1 + h2 * y2 + h3 * t + h4 * t;
    double lo = fmin(y1, y2), hi = fmax(y1, y2);
    return v < lo ? lo : v > hi ? hi : v;
}

float clvr_tf_opacity(const clvr_tf *tf, float x)
{
    x = clamp01(x);
    if (!tf->num_opacity) return 0.0f; /* not initialised */
    long k = find_segment(tf->opacity, tf->num_opacity, x);
    if (k < 0 || k >= (long)tf->num_opacity - 1) return tf->opacity[4 * (size_t)(k < 0 ? 0 : k) + 1];
    const float *p = tf->opacity + 4 * (size_t)k, *q = p + 4;
    double s = ((double)x - p[0]) / ((double)q[0] - p[0]);
    return clamp01((float)opacity_segment(s, p[1], q[1], p[2], p[3]));
}

/* ------------------------------------------------------------ tf object */

void clvr_tf_free(clvr_tf *tf)
{
    if (!tf) return;
    free(tf->colors);
    free(tf->opacity);
    memset(tf, 0, sizeof *tf);
}

static clvr_status map_points(const builtin_map *m, float **out, uint32_t *n, clvr_error *err)
{
    float *p = malloc(sizeof(float) * 4 * m->count);
    if (!p) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for colour map %s", m->name);
    for (uint32_t i = 0; i < m->count; ++i) {
        p[4 * i] = m->points[i][0] * m->x_scale;
        for (int c = 1; c < 4; ++c) p[4 * i + c] = m->points[i][c];
    }
    p[4 * (m->count - 1)] = 1.0f; /* exactly, whatever the scale's rounding */
    *out = p;
    *n = m->count;
    return CLVR_OK;
}

clvr_status clvr_tf_set_colormap(clvr_tf *tf, const char *colormap, clvr_error *err)
{
    const builtin_map *m = find_map(colormap ? colormap : "cool-warm");
    if (!m)
        return clvr_error_set(err, CLVR_ERR_USAGE, "unknown colour map \"%s\"; expected one of: %s", colormap,
                              clvr_tf_colormap_names());
    float *p;
    uint32_t n;
    clvr_status s = map_points(m, &p, &n, err);
    if (s != CLVR_OK) return s;
    free(tf->colors);
    tf->colors = p;
    tf->num_colors = n;
    tf->space = m->space;
    snprintf(tf->name, sizeof tf->name, "%s", m->name);
    return CLVR_OK;
}

clvr_status clvr_tf_init(clvr_tf *tf, const char *colormap, clvr_error *err)
{
    clvr_tf_free(tf);
    clvr_status s = clvr_tf_set_colormap(tf, colormap, err);
    if (s != CLVR_OK) return s;
    tf->opacity = malloc(sizeof(float) * 8);
    if (!tf->opacity) {
        clvr_tf_free(tf);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the opacity curve");
    }
    const float ramp[8] = {0.0f, 0.0f, 0.5f, 0.0f, 1.0f, 1.0f, 0.5f, 0.0f};
    memcpy(tf->opacity, ramp, sizeof ramp);
    tf->num_opacity = 2;
    tf->opacity_set = 0;
    tf->range_lo = 0.0f;
    tf->range_hi = 1.0f;
    tf->range_set = 0;
    tf->density = 1.0f;
    tf->extent = 0.0f;
    tf->table_size = CLVR_TF_DEFAULT_SIZE;
    return CLVR_OK;
}

void clvr_tf_set_extent(clvr_tf *tf, const float lo[3], const float hi[3])
{
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]);
    double d = sqrt(d2);
    tf->extent = isfinite(d) && d > 0.0 && d < 3.0e38 ? (float)d : 0.0f;
}

float clvr_tf_extinction_scale(const clvr_tf *tf)
{
    return CLVR_TF_DIAGONAL_DEPTH / (tf->extent > 0.0f ? tf->extent : 1.0f);
}

uint32_t clvr_tf_table_size(const clvr_tf *tf) { return tf->table_size >= 2 ? tf->table_size : CLVR_TF_DEFAULT_SIZE; }

void clvr_tf_bake(const clvr_tf *tf, float *rgba, uint32_t n)
{
    float scale = clvr_tf_extinction_scale(tf);
    for (uint32_t i = 0; i < n; ++i) {
        float x = n > 1 ? (float)((double)i / (double)(n - 1)) : 0.0f, c[3];
        clvr_tf_color(tf, x, c);
        for (int k = 0; k < 3; ++k) rgba[4 * (size_t)i + k] = clvr_image_srgb_decode(c[k]);
        rgba[4 * (size_t)i + 3] = clvr_tf_opacity(tf, x) * scale;
    }
}

/* ------------------------------------------------------------ parsing
 * Both formats fill a pending description first and commit it to the tf
 * only when the whole file was read, so a failed load leaves tf unchanged. */

typedef struct pending {
    int have_colors, have_space, have_opacity, have_range, have_density, have_table;
    uint32_t space;
    char name[64];
    float *colors, *opacity;
    uint32_t num_colors, cap_colors, num_opacity, cap_opacity;
    float lo, hi, density;
    uint32_t table;
} pending;

static void pending_free(pending *p)
{
    free(p->colors);
    free(p->opacity);
}

static clvr_status push4(float **arr, uint32_t *n, uint32_t *cap, const float v[4], const char *name,
                         clvr_error *err)
{
    if (*n == *cap) {
        uint32_t nc = *cap ? *cap * 2 : 16;
        if (nc < *cap || nc > (1u << 26))
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: more than %u control points", name, 1u << 26);
        float *p = realloc(*arr, sizeof(float) * 4 * (size_t)nc);
        if (!p) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory for control points", name);
        *arr = p;
        *cap = nc;
    }
    memcpy(*arr + 4 * (size_t)*n, v, sizeof(float) * 4);
    ++*n;
    return CLVR_OK;
}

static void commit(clvr_tf *tf, pending *p)
{
    if (p->have_colors) {
        free(tf->colors);
        tf->colors = p->colors;
        tf->num_colors = p->num_colors;
        p->colors = NULL;
        snprintf(tf->name, sizeof tf->name, "%s", p->name);
    }
    if (p->have_space) tf->space = p->space;
    if (p->have_opacity) {
        free(tf->opacity);
        tf->opacity = p->opacity;
        tf->num_opacity = p->num_opacity;
        tf->opacity_set = 1;
        p->opacity = NULL;
    }
    if (p->have_range) {
        tf->range_lo = p->lo;
        tf->range_hi = p->hi;
        tf->range_set = 1;
    }
    if (p->have_density) tf->density *= p->density;
    if (p->have_table) tf->table_size = p->table;
}

static const char *k_space_names[CLVR_TF_SPACE_COUNT] = {"RGB", "Lab", "Diverging", "HSV", "Step"};

static int parse_space(const char *s, size_t len, uint32_t *out)
{
    for (uint32_t i = 0; i < CLVR_TF_SPACE_COUNT; ++i)
        if (strlen(k_space_names[i]) == len && !strncasecmp(s, k_space_names[i], len)) { *out = i; return 1; }
    if (len == 13 && !strncasecmp(s, "Lab/CIEDE2000", 13)) { *out = CLVR_TF_SPACE_LAB; return 1; }
    return 0;
}

/* A value that must lie in [0, 1]: exporters write rounding noise such as
 * 1.0000001, so a millionth beyond is accepted (and clamped). */
static int unit_value(double v) { return v >= -1e-6 && v <= 1.0 + 1e-6; }

static float clamp_unit(float v) { return v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v; }

/* ---------------------------------------------- text format */

/* Strict float: the whole token, finite, within float range. */
static int parse_float_token(const char *tok, float *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(tok, &end);
    if (end == tok || *end || !isfinite(v) || fabs(v) > FLT_MAX) return 0;
    *out = (float)v;
    return 1;
}

#define TEXT_MAX_TOKENS 8

static clvr_status parse_text(pending *p, const char *text, size_t len, const char *name, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    size_t pos = 0;
    uint32_t line = 0;
    int used_colormap = 0;
    char buf[1024];
    while (pos < len) {
        ++line;
        size_t start = pos;
        while (pos < len && text[pos] != '\n') ++pos;
        size_t end = pos;
        if (pos < len) ++pos; /* the '\n' */
        if (end - start >= sizeof buf)
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u: line longer than %zu characters", name, line,
                                  sizeof buf - 1);
        memcpy(buf, text + start, end - start);
        buf[end - start] = '\0';
        for (size_t i = 0; i < end - start; ++i)
            if (buf[i] == '\0')
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u: NUL byte in a text file", name, line);
        char *hash = strchr(buf, '#');
        if (hash) *hash = '\0';
        char *tok[TEXT_MAX_TOKENS + 1];
        int nt = 0;
        char *save = NULL;
        for (char *t = strtok_r(buf, " \t\r\f\v", &save); t; t = strtok_r(NULL, " \t\r\f\v", &save)) {
            if (nt == TEXT_MAX_TOKENS)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u: too many values on one line", name, line);
            tok[nt++] = t;
        }
        if (nt == 0) continue;
        const char *kw = tok[0];
        float v[4];
        if (!strcmp(kw, "color") || !strcmp(kw, "colour")) {
            if (nt != 5)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u: expected `color x r g b` (4 numbers), got %d",
                                      name, line, nt - 1);
            for (int i = 0; i < 4; ++i) {
                if (!parse_float_token(tok[1 + i], &v[i]) || !unit_value(v[i]))
                    return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                          "%s:%u: color: \"%s\" is not a number in [0, 1] (expected `color x r g b`, "
                                          "x a position in the window, r g b sRGB values)",
                                          name, line, tok[1 + i]);
                v[i] = clamp_unit(v[i]);
            }
            if (used_colormap)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: color lines after a colormap line; use one or the other", name, line);
            if (p->num_colors && v[0] < p->colors[4 * (size_t)(p->num_colors - 1)])
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: color position %g is before the previous one; positions must not decrease",
                                      name, line, (double)v[0]);
            s = push4(&p->colors, &p->num_colors, &p->cap_colors, v, name, err);
            if (s != CLVR_OK) return s;
            p->have_colors = 1;
            snprintf(p->name, sizeof p->name, "custom");
        } else if (!strcmp(kw, "opacity")) {
            if (nt != 3 && nt != 5)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: expected `opacity x a` or `opacity x a midpoint sharpness`, got %d numbers",
                                      name, line, nt - 1);
            v[2] = 0.5f;
            v[3] = 0.0f;
            for (int i = 0; i < nt - 1; ++i) {
                if (!parse_float_token(tok[1 + i], &v[i]) || !unit_value(v[i]))
                    return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                          "%s:%u: opacity: \"%s\" is not a number in [0, 1]", name, line, tok[1 + i]);
                v[i] = clamp_unit(v[i]);
            }
            if (p->num_opacity && v[0] < p->opacity[4 * (size_t)(p->num_opacity - 1)])
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: opacity position %g is before the previous one; positions must not "
                                      "decrease",
                                      name, line, (double)v[0]);
            s = push4(&p->opacity, &p->num_opacity, &p->cap_opacity, v, name, err);
            if (s != CLVR_OK) return s;
            p->have_opacity = 1;
        } else if (!strcmp(kw, "range")) {
            if (nt != 3 || !parse_float_token(tok[1], &v[0]) || !parse_float_token(tok[2], &v[1]) || !(v[0] < v[1]))
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: expected `range lo hi` with two finite numbers, lo < hi", name, line);
            p->lo = v[0];
            p->hi = v[1];
            p->have_range = 1;
        } else if (!strcmp(kw, "density")) {
            if (nt != 2 || !parse_float_token(tok[1], &v[0]) || v[0] < 0.0f)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: expected `density d` with one finite number >= 0", name, line);
            p->density = v[0];
            p->have_density = 1;
        } else if (!strcmp(kw, "colormap") || !strcmp(kw, "colourmap")) {
            if (nt != 2)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u: expected `colormap NAME`, NAME one of: %s",
                                      name, line, clvr_tf_colormap_names());
            const builtin_map *m = find_map(tok[1]);
            if (!m)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u: unknown colormap \"%s\"; expected one of: %s",
                                      name, line, tok[1], clvr_tf_colormap_names());
            if (p->have_colors)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: a colormap line after color lines or another colormap; use one", name,
                                      line);
            s = map_points(m, &p->colors, &p->num_colors, err);
            if (s != CLVR_OK) return s;
            p->cap_colors = p->num_colors;
            p->have_colors = used_colormap = 1;
            if (!p->have_space) p->space = m->space;
            snprintf(p->name, sizeof p->name, "%s", m->name);
        } else if (!strcmp(kw, "colorspace") || !strcmp(kw, "colourspace")) {
            if (nt != 2 || !parse_space(tok[1], strlen(tok[1]), &p->space))
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: expected `colorspace S`, S one of RGB, Lab, Diverging, HSV, Step", name,
                                      line);
            p->have_space = 1;
        } else if (!strcmp(kw, "table")) {
            float n;
            if (nt != 2 || !parse_float_token(tok[1], &n) || n != floorf(n) || n < 2.0f ||
                n > (float)CLVR_TF_MAX_TABLE)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s:%u: expected `table N` with an integer N in [2, %u]", name, line,
                                      CLVR_TF_MAX_TABLE);
            p->table = (uint32_t)n;
            p->have_table = 1;
        } else {
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                  "%s:%u: unknown keyword \"%s\"; expected color, opacity, range, density, colormap, "
                                  "colorspace or table",
                                  name, line, kw);
        }
    }
    if (!p->have_colors && !p->have_opacity && !p->have_range && !p->have_density && !p->have_space &&
        !p->have_table)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s:%u: no transfer-function lines (color, opacity, range, density, colormap, ...)", name,
                              line ? line : 1);
    return CLVR_OK;
}

/* ---------------------------------------------- JSON (ParaView colour maps; parser: json.c) */

/* Reads a numeric array of groups of 4 into points (stride 4), checking
 * every value; positions stay in data space (normalise_points rescales). */
static clvr_status jpoints(const clvr_json *p, clvr_error *err, const clvr_json_node *arr, const char *key,
                           int opacity, float **out, uint32_t *num)
{
    if (arr->type != CLVR_JSON_ARRAY)
        return clvr_json_fail(p, err, arr->line, arr->col, "\"%s\" must be an array of numbers, found %s", key,
                              clvr_json_type_name(arr->type));
    if (arr->count == 0 || arr->count % 4)
        return clvr_json_fail(p, err, arr->line, arr->col,
                              "\"%s\" has %u numbers; expected a non-empty multiple of 4 (%s)", key, arr->count,
                              opacity ? "x, opacity, midpoint, sharpness" : "x, r, g, b");
    uint32_t n = arr->count / 4;
    float *pts = malloc(sizeof(float) * arr->count);
    if (!pts) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory for %s", p->name, key);
    long c = arr->child;
    for (uint32_t i = 0; i < arr->count; ++i, c = p->nodes[c].next) {
        const clvr_json_node *v = &p->nodes[c];
        int comp = (int)(i % 4);
        if (v->type != CLVR_JSON_NUMBER) {
            free(pts);
            return clvr_json_fail(p, err, v->line, v->col, "\"%s\"[%u] must be a number, found %s", key, i,
                                  clvr_json_type_name(v->type));
        }
        /* Position: any finite float; others (colour, opacity, midpoint,
         * sharpness) in [0, 1]. */
        int bad = comp == 0 ? !(fabs(v->num) <= FLT_MAX) : !unit_value(v->num);
        if (!bad && comp == 0 && i >= 4 && (float)v->num < pts[i - 4]) {
            free(pts);
            return clvr_json_fail(p, err, v->line, v->col,
                                  "\"%s\"[%u] = %g is smaller than the previous position; positions must not decrease",
                                  key, i, v->num);
        }
        if (bad) {
            free(pts);
            return clvr_json_fail(p, err, v->line, v->col, "\"%s\"[%u] = %g is out of range (expected %s)", key, i,
                                  v->num, comp == 0 ? "a finite position" : "a value in [0, 1]");
        }
        pts[i] = comp == 0 ? (float)v->num : (float)fmin(fmax(v->num, 0.0), 1.0);
    }
    float x0 = pts[0], x1 = pts[4 * (n - 1)];
    if (n > 1 && !(x1 > x0)) {
        free(pts);
        return clvr_json_fail(p, err, arr->line, arr->col, "\"%s\": all %u positions are equal (%g); expected a span",
                              key, n, (double)x0);
    }
    *out = pts;
    *num = n;
    return CLVR_OK;
}

/* Data-space positions to [0, 1] over the common span [lo, hi]. */
static void normalise_points(float *pts, uint32_t n, double lo, double hi)
{
    for (uint32_t i = 0; i < n; ++i) {
        double x = hi > lo ? ((double)pts[4 * i] - lo) / (hi - lo) : 0.0;
        pts[4 * i] = (float)(x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x);
    }
}

/* The "Name" string of a colour-map object, NULL when it has none. */
static const char *json_map_name(const clvr_json *p, const clvr_json_node *obj)
{
    if (obj->type != CLVR_JSON_OBJECT) return NULL;
    for (long c = obj->child; c >= 0; c = p->nodes[c].next)
        if (clvr_json_key_is(p, &p->nodes[c], "Name") && p->nodes[c].type == CLVR_JSON_STRING)
            return p->arena + p->nodes[c].str;
    return NULL;
}

static clvr_status parse_json(pending *pd, const char *text, size_t len, const char *name, const char *preset,
                              clvr_error *err)
{
    clvr_json p;
    clvr_status s = clvr_json_parse(text, len, name, &p, err);
    if (s != CLVR_OK) return s;
    const clvr_json_node *obj = &p.nodes[p.root];
    if (obj->type == CLVR_JSON_ARRAY) {
        if (obj->count == 0) {
            s = clvr_json_fail(&p, err, obj->line, obj->col, "empty array: expected at least one colour-map object");
            goto done;
        }
        if (preset) {
            /* A presets file: the object whose "Name" is the preset. */
            const clvr_json_node *found = NULL;
            char names[768];
            size_t nl = 0;
            int more = 0;
            names[0] = '\0';
            for (long c = obj->child; c >= 0 && !found; c = p.nodes[c].next) {
                const char *mn = json_map_name(&p, &p.nodes[c]);
                if (!mn) continue;
                if (!strcmp(mn, preset)) found = &p.nodes[c];
                else if (nl + strlen(mn) + 8 < sizeof names)
                    nl += (size_t)snprintf(names + nl, sizeof names - nl, "%s\"%s\"", nl ? ", " : "", mn);
                else more = 1;
            }
            if (!found) {
                s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: no colour map named \"%s\"; the file has %s%s", name,
                                   preset, nl ? names : "no named maps", more ? ", ..." : "");
                goto done;
            }
            obj = found;
        } else {
            obj = &p.nodes[obj->child]; /* ParaView exports a list; the first map is used */
        }
    } else if (preset && !(json_map_name(&p, obj) && !strcmp(json_map_name(&p, obj), preset))) {
        const char *mn = json_map_name(&p, obj);
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: no colour map named \"%s\"; the file has %s%s%s", name, preset,
                           mn ? "\"" : "no named maps", mn ? mn : "", mn ? "\"" : "");
        goto done;
    }
    if (obj->type != CLVR_JSON_OBJECT) {
        s = clvr_json_fail(&p, err, obj->line, obj->col,
                     "expected a ParaView colour map: an array of objects with \"RGBPoints\", found %s",
                     clvr_json_type_name(obj->type));
        goto done;
    }
    const clvr_json_node *space = NULL, *nm = NULL, *rgb = NULL, *pts = NULL;
    for (long c = obj->child; c >= 0; c = p.nodes[c].next) {
        const clvr_json_node *m = &p.nodes[c];
        const clvr_json_node **slot = clvr_json_key_is(&p, m, "ColorSpace") ? &space
                           : clvr_json_key_is(&p, m, "Name")     ? &nm
                           : clvr_json_key_is(&p, m, "RGBPoints") ? &rgb
                           : clvr_json_key_is(&p, m, "Points")   ? &pts
                                                        : NULL;
        if (!slot) continue; /* other ParaView keys (NanColor, Creator, ...) do not apply */
        if (*slot) {
            s = clvr_json_fail(&p, err, m->kline, m->kcol, "duplicate key \"%s\"", p.arena + m->key);
            goto done;
        }
        *slot = m;
    }
    if (!rgb) {
        s = clvr_json_fail(&p, err, obj->line, obj->col,
                           "colour-map object has no \"RGBPoints\" (expected [x, r, g, b, ...])");
        goto done;
    }
    pd->space = CLVR_TF_SPACE_RGB;
    if (space) {
        if (space->type != CLVR_JSON_STRING || !parse_space(p.arena + space->str, space->slen, &pd->space)) {
            s = clvr_json_fail(&p, err, space->line, space->col,
                         "\"ColorSpace\" must be one of \"RGB\", \"Lab\", \"Lab/CIEDE2000\", \"Diverging\", \"HSV\", "
                         "\"Step\"");
            goto done;
        }
    }
    pd->have_space = 1;
    if (nm && nm->type != CLVR_JSON_STRING) {
        s = clvr_json_fail(&p, err, nm->line, nm->col, "\"Name\" must be a string, found %s",
                           clvr_json_type_name(nm->type));
        goto done;
    }
    snprintf(pd->name, sizeof pd->name, "%s", nm ? p.arena + nm->str : "custom");
    s = jpoints(&p, err, rgb, "RGBPoints", 0, &pd->colors, &pd->num_colors);
    if (s != CLVR_OK) goto done;
    pd->have_colors = 1;
    if (pts) {
        s = jpoints(&p, err, pts, "Points", 1, &pd->opacity, &pd->num_opacity);
        if (s != CLVR_OK) goto done;
        pd->have_opacity = 1;
    }
    {
        /* Both lists are in data space, as ParaView exports them: one common
         * span (their union) rescales both, so their relative placement is
         * kept (each function is constant beyond its ends, as in VTK), and
         * the span is the window unless --range overrides it, which then
         * stretches both together as ParaView's "Rescale to custom range". */
        double lo = pd->colors[0], hi = pd->colors[4 * (pd->num_colors - 1)];
        if (pd->have_opacity) {
            lo = fmin(lo, pd->opacity[0]);
            hi = fmax(hi, pd->opacity[4 * (pd->num_opacity - 1)]);
        }
        normalise_points(pd->colors, pd->num_colors, lo, hi);
        if (pd->have_opacity) normalise_points(pd->opacity, pd->num_opacity, lo, hi);
        if (hi > lo && (float)hi > (float)lo) {
            pd->lo = (float)lo;
            pd->hi = (float)hi;
            pd->have_range = 1;
        }
    }
done:
    clvr_json_free(&p);
    return s;
}

/* ------------------------------------------------------------ entry points */

clvr_status clvr_tf_parse(clvr_tf *tf, const char *text, size_t len, const char *name, clvr_error *err)
{
    return clvr_tf_parse_preset(tf, text, len, name, NULL, err);
}

clvr_status clvr_tf_parse_preset(clvr_tf *tf, const char *text, size_t len, const char *name, const char *preset,
                                 clvr_error *err)
{
    pending p = {0};
    p.density = 1.0f;
    size_t i = 0;
    /* A UTF-8 byte-order mark is not content. */
    if (len >= 3 && !memcmp(text, "\xEF\xBB\xBF", 3)) i = 3;
    size_t j = i;
    while (j < len && (text[j] == ' ' || text[j] == '\t' || text[j] == '\r' || text[j] == '\n')) ++j;
    clvr_status s;
    if (j < len && (text[j] == '[' || text[j] == '{')) s = parse_json(&p, text + i, len - i, name, preset, err);
    else if (preset)
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: a preset name (\"%s\") applies to ParaView JSON only", name,
                           preset);
    else s = parse_text(&p, text + i, len - i, name, err);
    if (s == CLVR_OK) commit(tf, &p);
    pending_free(&p);
    return s;
}

clvr_status clvr_tf_load(clvr_tf *tf, const char *path, clvr_error *err)
{
    FILE *f = fopen(path, "rb");
    const char *preset = NULL;
    char file[4096];
    if (!f) {
        /* FILE:PRESET: the first ':' whose left part opens as a file. */
        int open_errno = errno;
        for (const char *c = strchr(path, ':'); c && !f; c = strchr(c + 1, ':')) {
            size_t n = (size_t)(c - path);
            if (n == 0 || n >= sizeof file || c[1] == '\0') continue;
            memcpy(file, path, n);
            file[n] = '\0';
            f = fopen(file, "rb");
            if (f) preset = c + 1;
        }
        if (!f)
            return clvr_error_set(err, CLVR_ERR_IO, "cannot open transfer function %s: %s", path,
                                  strerror(open_errno));
        path = file;
    }
    char *buf = malloc(CLVR_TF_MAX_FILE_BYTES + 1);
    if (!buf) {
        fclose(f);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading %s", path);
    }
    size_t n = fread(buf, 1, CLVR_TF_MAX_FILE_BYTES + 1, f);
    int rerr = ferror(f);
    fclose(f);
    clvr_status s;
    if (rerr) s = clvr_error_set(err, CLVR_ERR_IO, "cannot read transfer function %s: read error", path);
    else if (n > CLVR_TF_MAX_FILE_BYTES)
        s = clvr_error_set(err, CLVR_ERR_IO, "transfer function %s is larger than %u MiB; is it the right file?", path,
                           CLVR_TF_MAX_FILE_BYTES >> 20);
    else s = clvr_tf_parse_preset(tf, buf, n, path, preset, err);
    free(buf);
    return s;
}

clvr_status clvr_tf_from_options(clvr_tf *tf, const char *colormap, const char *tf_file, int range_set,
                                 float range_lo, float range_hi, float density, float scalar_min, float scalar_max,
                                 clvr_error *err)
{
    clvr_status s = clvr_tf_init(tf, colormap, err);
    if (s == CLVR_OK && tf_file) s = clvr_tf_load(tf, tf_file, err);
    if (s != CLVR_OK) return s;
    if (!(isfinite(density) && density >= 0.0f)) {
        s = clvr_error_set(err, CLVR_ERR_USAGE, "--density %g: expected a finite number >= 0", (double)density);
    } else if (range_set) {
        if (!(isfinite(range_lo) && isfinite(range_hi) && range_lo < range_hi))
            s = clvr_error_set(err, CLVR_ERR_USAGE, "--range %g %g: expected finite LO < HI", (double)range_lo,
                               (double)range_hi);
        tf->range_lo = range_lo;
        tf->range_hi = range_hi;
        tf->range_set = 1;
    } else if (!tf->range_set) {
        if (!(isfinite(scalar_min) && isfinite(scalar_max) && scalar_min <= scalar_max)) {
            s = clvr_error_set(err, CLVR_ERR_BAD_VALUE,
                               "scalar range [%g, %g] is not finite; give the window with --range LO HI",
                               (double)scalar_min, (double)scalar_max);
        } else {
            tf->range_lo = scalar_min;
            tf->range_hi = scalar_max;
            /* A constant field still needs a window; centre it on the value. */
            if (!(tf->range_hi > tf->range_lo)) {
                float d = fmaxf(fabsf(scalar_min) * 1e-3f, 1e-3f);
                tf->range_lo = scalar_min - d;
                tf->range_hi = scalar_min + d;
            }
        }
    }
    if (s == CLVR_OK) tf->density *= density;
    if (s != CLVR_OK) clvr_tf_free(tf);
    return s;
}
