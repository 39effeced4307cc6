/* sfc.h: space-filling-curve keys of quantized 3D points, compiled twice
 * (host reference/tests and kernels) so both sides produce the very same
 * bits.
 *
 * Hilbert: the non-recursive Cartesian-to-Hilbert transform of Butz (1971),
 * in the simplified form of Moore and of Skilling ("Programming the Hilbert
 * curve", AIP Conf. Proc. 707, 2004): an "inverse undo" sweep from the top
 * bit down, a Gray encode, then the bits of the three transposed words are
 * interleaved (x highest) into one key of 3 * bits bits. With bits == 16
 * this is the paper's 48-bit key (section 3.2.1). The curve starts at the
 * origin, so keys [0, 8^k) cover exactly the cube [0, 2^k)^3, and
 * consecutive keys are face-adjacent cells.
 *
 * Morton: the same quantized coordinates with their bits interleaved, kept
 * for comparison (paper Fig. 4). */
#ifndef CLVR_SFC_H
#define CLVR_SFC_H

#include "clvr_shared.h"

/* Spreads the low 16 bits of v so that bit i moves to bit 3i. */
CLVR_FORCE_INLINE clvr_u64 clvr_sfc_spread3(clvr_u32 v)
{
    clvr_u64 x = v & 0xffffu;
    x = (x | (x << 32)) & 0x1f00000000ffffull;
    x = (x | (x << 16)) & 0x1f0000ff0000ffull;
    x = (x | (x << 8)) & 0x100f00f00f00f00full;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
}

/* Inverse of clvr_sfc_spread3. */
CLVR_INLINE clvr_u32 clvr_sfc_compact3(clvr_u64 x)
{
    x &= 0x1249249249249249ull;
    x = (x | (x >> 2)) & 0x10c30c30c30c30c3ull;
    x = (x | (x >> 4)) & 0x100f00f00f00f00full;
    x = (x | (x >> 8)) & 0x1f0000ff0000ffull;
    x = (x | (x >> 16)) & 0x1f00000000ffffull;
    x = (x | (x >> 32)) & 0xffffull;
    return (clvr_u32)x;
}

/* Morton key of (x, y, z), each < 2^16: x's bits are the most significant of
 * each triple. */
CLVR_FORCE_INLINE clvr_u64 clvr_morton3(clvr_u32 x, clvr_u32 y, clvr_u32 z)
{
    return (clvr_sfc_spread3(x) << 2) | (clvr_sfc_spread3(y) << 1) | clvr_sfc_spread3(z);
}

/* Hilbert key of (x, y, z), each < 2^bits, 1 <= bits <= 16; the key has
 * 3 * bits significant bits. */
CLVR_INLINE clvr_u64 clvr_hilbert3_bits(clvr_u32 x, clvr_u32 y, clvr_u32 z, clvr_u32 bits)
{
    clvr_u32 X0 = x, X1 = y, X2 = z, t;
    const clvr_u32 M = 1u << (bits - 1u);
    /* Inverse undo: for each bit from the top, either invert the lower bits
     * of X0 or exchange them with the axis being looked at. */
    for (clvr_u32 Q = M; Q > 1u; Q >>= 1) {
        const clvr_u32 P = Q - 1u;
        if (X0 & Q) X0 ^= P;
        /* axis 0 against itself: an exchange is a no-op */
        if (X1 & Q) X0 ^= P;
        else { t = (X0 ^ X1) & P; X0 ^= t; X1 ^= t; }
        if (X2 & Q) X0 ^= P;
        else { t = (X0 ^ X2) & P; X0 ^= t; X2 ^= t; }
    }
    /* Gray encode. */
    X1 ^= X0;
    X2 ^= X1;
    t = 0;
    for (clvr_u32 Q = M; Q > 1u; Q >>= 1)
        if (X2 & Q) t ^= Q - 1u;
    X0 ^= t;
    X1 ^= t;
    X2 ^= t;
    /* The transposed form holds the key's bits round-robin: X0 carries the
     * most significant bit of every triple. */
    return (clvr_sfc_spread3(X0) << 2) | (clvr_sfc_spread3(X1) << 1) | clvr_sfc_spread3(X2);
}

/* Program-scope constant tables: __constant on the device, static const on
 * the host (a plain const would have external linkage in C). */
#ifdef __OPENCL_VERSION__
#define CLVR_SFC_TABLE __constant
#else
#define CLVR_SFC_TABLE static const
#endif

/* The same curve as a Butz-Moore state machine, two levels (6 key bits) per
 * step: clvr_hilbert3_table[state * 64 + m] for the 6 Morton bits m = x1 y1
 * z1 x0 y0 z0 of two levels holds the 6 Hilbert digits of those levels
 * (bits 0..5) and the state of the next two levels (bits 6..10). The 24
 * states are the orientations (axis permutation + reflection) that the
 * curve's sub-cubes take; state 0 is the whole cube. The table was derived
 * from clvr_hilbert3_bits itself: for every octant, the isometry mapping the
 * sub-cube's keys onto the next-smaller curve was found by exhaustive search
 * (and checked for orders 2..6), then the states were enumerated by
 * composing those isometries. tests/test_sfc.c checks that both encoders
 * agree. Eight table steps replace the 15-iteration branchy sweep, which
 * made the key kernel compute-bound on CPU devices. */
CLVR_SFC_TABLE clvr_u16 clvr_hilbert3_table[24 * 64] = {
     448,  519,  577,  646,  707,  132,   66,   69,  392,    9,  783,  846,  907,  138,   76,  141,  /* state 0 */
     990, 1049,  221,  218,  607,  664, 1116,   27,   80,  145,  211,   18,  279,  342,  404,   21,
    1212,  379,  317,  314, 1023, 1080,  638,  697, 1268,  373,  307,  370,  247,   54, 1328,  881,
     608,  679, 1123,   36,  481,  550,  418,  421,  104,  169,  235,   42,  303,  366,  428,   45,
       0, 1347,  839,  580,  385,  450,  774,  453, 1468, 1151,  699, 1528,  573,  446,  570,  825,  /* state 1 */
     136,  971,   73,  586,  335,  460,  270,  589, 1076,  759,  693,  118,  563, 1200,  690,  305,
    1118,  415, 1497,  792,  733,  924,  730,   91,  416,   33,  807,  870,  931,  162,  100,  165,
     464,  535,  593,  662,  723,  148,   82,   85,  488,  559,  617,  686,  747,  172,  106,  109,
     576,  647, 1091,    4,  449,  518,  386,  389,   72,  137,  203,   10,  271,  334,  396,   13,  /* state 2 */
    1532,  891, 1407, 1464,  829,  826,  510,  569, 1332,  885,  951,  182,  819,  882, 1264,  369,
    1374, 1433,  479,  536,  925,  922,  732,  155,  400,   17,  791,  854,  915,  146,   84,  149,
     480,  551,  609,  678,  739,  164,   98,  101,  424,   41,  815,  878,  939,  170,  108,  173,
     246, 1013, 1329, 1010,   55, 1396,  880,  627, 1034,  201, 1037, 1294, 1419, 1096,  652, 1487,  /* state 3 */
    1006, 1065,  237,  234,  623,  680, 1132,   43,  982, 1041,  213,  210,  599,  656, 1108,   19,
     184, 1019,  121,  634,  383,  508,  318,  637, 1028,  711,  645,   70,  515, 1152,  642,  257,
     742,  103, 1125,  228, 1185,  288, 1122,  419,   88,  153,  219,   26,  287,  350,  412,   29,
    1186, 1251, 1189,  292, 1121,  224, 1510, 1319, 1244,  349,  283,  346,  223,   30, 1304,  857,  /* state 4 */
    1196,  363,  301,  298, 1007, 1064,  622,  681, 1172,  339,  277,  274,  983, 1040,  598,  657,
     254, 1021, 1337, 1018,   63, 1404,  888,  635, 1026,  193, 1029, 1286, 1411, 1088,  644, 1479,
     176, 1011,  113,  626,  375,  500,  310,  629, 1036,  719,  653,   78,  523, 1160,  650,  265,
    1250, 1253, 1187,  356, 1377, 1446,  992, 1063, 1260,  365,  299,  362,  239,   46, 1320,  873,  /* state 5 */
    1180,  347,  285,  282,  991, 1048,  606,  665, 1236,  341,  275,  338,  215,   22, 1296,  849,
    1022, 1081,  253,  250,  639,  696, 1148,   59,  112,  177,  243,   50,  311,  374,  436,   53,
    1282, 1285,  961, 1030, 1475,  836, 1344, 1415, 1292,  845,  911,  142,  779,  842, 1224,  329,
     128,  963,   65,  578,  327,  452,  262,  581, 1084,  767,  701,  126,  571, 1208,  698,  313,  /* state 6 */
     734,   95, 1117,  220, 1177,  280, 1114,  411,   96,  161,  227,   34,  295,  358,  420,   37,
       8, 1355,  847,  588,  393,  458,  782,  461, 1460, 1143,  691, 1520,  565,  438,  562,  817,
     592,  663, 1107,   20,  465,  534,  402,  405,  616,  687, 1131,   44,  489,  558,  426,  429,
      64,  129,  195,    2,  263,  326,  388,    5,  926, 1373,  159,  988, 1241, 1370,  344,  475,  /* state 7 */
    1340,  893,  959,  190,  827,  890, 1272,  377,  160,  995,   97,  610,  359,  484,  294,  613,
     584,  655, 1099,   12,  457,  526,  394,  397,   16, 1363,  855,  596,  401,  466,  790,  469,
    1524,  883, 1399, 1456,  821,  818,  502,  561,   40, 1387,  879,  620,  425,  490,  814,  493,
    1442,  929, 1059,  736, 1445, 1254,  548, 1191,  766,  127, 1149,  252, 1209,  312, 1146,  443,  /* state 8 */
    1052,  735,  669,   94,  539, 1176,  666,  281, 1474, 1283,  705,  896, 1477,  772, 1158, 1223,
    1452, 1135,  683, 1512,  557,  430,  554,  809,  624,  695, 1139,   52,  497,  566,  434,  437,
    1428, 1111,  659, 1488,  533,  406,  530,  785, 1484,  843, 1359, 1416,  781,  778,  462,  521,
     384,    1,  775,  838,  899,  130,   68,  133,  222,  989, 1305,  986,   31, 1372,  856,  603,  /* state 9 */
     456,  527,  585,  654,  715,  140,   74,   77,  144,  979,   81,  594,  343,  468,  278,  597,
    1276,  381,  315,  378,  255,   62, 1336,  889,   32, 1379,  871,  612,  417,  482,  806,  485,
    1204,  371,  309,  306, 1015, 1072,  630,  689,  168, 1003,  105,  618,  367,  492,  302,  621,
    1058,  225, 1061, 1318, 1443, 1120,  676, 1511, 1150,  447, 1529,  824,  765,  956,  762,  123,  /* state 10 */
    1068,  751,  685,  110,  555, 1192,  682,  297,  496,  567,  625,  694,  755,  180,  114,  117,
    1436, 1119,  667, 1496,  541,  414,  538,  793, 1154, 1219, 1157,  260, 1089,  192, 1478, 1287,
    1044,  727,  661,   86,  531, 1168,  658,  273, 1164,  331,  269,  266,  975, 1032,  590,  649,
     758,  119, 1141,  244, 1201,  304, 1138,  435,  632,  703, 1147,   60,  505,  574,  442,  445,  /* state 11 */
    1482, 1291,  713,  904, 1485,  780, 1166, 1231, 1476,  835, 1351, 1408,  773,  770,  454,  513,
    1134,  431, 1513,  808,  749,  940,  746,  107, 1382, 1441,  487,  544,  933,  930,  740,  163,
    1110,  407, 1489,  784,  725,  916,  722,   83,  472,  543,  601,  670,  731,  156,   90,   93,
    1506, 1315,  737,  928, 1509,  804, 1190, 1255, 1308,  861,  927,  158,  795,  858, 1240,  345,  /* state 12 */
     958, 1405,  191, 1020, 1273, 1402,  376,  507, 1410,  897, 1027,  704, 1413, 1222,  516, 1159,
    1516,  875, 1391, 1448,  813,  810,  494,  553, 1492,  851, 1367, 1424,  789,  786,  470,  529,
      48, 1395,  887,  628,  433,  498,  822,  501, 1420, 1103,  651, 1480,  525,  398,  522,  777,
    1314, 1317,  993, 1062, 1507,  868, 1376, 1447, 1324,  877,  943,  174,  811,  874, 1256,  361,  /* state 13 */
    1406, 1465,  511,  568,  957,  954,  764,  187,  432,   49,  823,  886,  947,  178,  116,  181,
    1500,  859, 1375, 1432,  797,  794,  478,  537, 1300,  853,  919,  150,  787,  850, 1232,  337,
    1218, 1221, 1155,  324, 1345, 1414,  960, 1031, 1228,  333,  267,  330,  207,   14, 1288,  841,
     950, 1397,  183, 1012, 1265, 1394,  368,  499, 1418,  905, 1035,  712, 1421, 1230,  524, 1167,  /* state 14 */
      56, 1403,  895,  636,  441,  506,  830,  509, 1412, 1095,  643, 1472,  517,  390,  514,  769,
    1390, 1449,  495,  552,  941,  938,  748,  171, 1366, 1425,  471,  528,  917,  914,  724,  147,
    1126,  423, 1505,  800,  741,  932,  738,   99,  408,   25,  799,  862,  923,  154,   92,  157,
    1014, 1073,  245,  242,  631,  688, 1140,   51,  238, 1005, 1321, 1002,   47, 1388,  872,  619,  /* state 15 */
    1290, 1293,  969, 1038, 1483,  844, 1352, 1423,  214,  981, 1297,  978,   23, 1364,  848,  595,
     120,  185,  251,   58,  319,  382,  444,   61,  934, 1381,  167,  996, 1249, 1378,  352,  483,
    1284,  837,  903,  134,  771,  834, 1216,  321,  152,  987,   89,  602,  351,  476,  286,  605,
    1042,  209, 1045, 1302, 1427, 1104,  660, 1495,  974, 1033,  205,  202,  591,  648, 1100,   11,  /* state 16 */
    1066,  233, 1069, 1326, 1451, 1128,  684, 1519, 1330, 1333, 1009, 1078, 1523,  884, 1392, 1463,
    1434,  921, 1051,  728, 1437, 1246,  540, 1183,  710,   71, 1093,  196, 1153,  256, 1090,  387,
    1060,  743,  677,  102,  547, 1184,  674,  289, 1530, 1339,  761,  952, 1533,  828, 1214, 1279,
    1142,  439, 1521,  816,  757,  948,  754,  115,  504,  575,  633,  702,  763,  188,  122,  125,  /* state 17 */
     750,  111, 1133,  236, 1193,  296, 1130,  427,  998, 1057,  229,  226,  615,  672, 1124,   35,
    1162, 1227, 1165,  268, 1097,  200, 1486, 1295, 1156,  323,  261,  258,  967, 1024,  582,  641,
     726,   87, 1109,  212, 1169,  272, 1106,  403,  600,  671, 1115,   28,  473,  542,  410,  413,
    1170, 1235, 1173,  276, 1105,  208, 1494, 1303, 1242, 1245, 1179,  348, 1369, 1438,  984, 1055,  /* state 18 */
    1194, 1259, 1197,  300, 1129,  232, 1518, 1327, 1188,  355,  293,  290,  999, 1056,  614,  673,
     718,   79, 1101,  204, 1161,  264, 1098,  395,  966, 1025,  197,  194,  583,  640, 1092,    3,
    1522, 1331,  753,  944, 1525,  820, 1206, 1271, 1338, 1341, 1017, 1086, 1531,  892, 1400, 1471,
    1234, 1237, 1171,  340, 1361, 1430,  976, 1047, 1258, 1261, 1195,  364, 1385, 1454, 1000, 1071,  /* state 19 */
    1178, 1243, 1181,  284, 1113,  216, 1502, 1311, 1252,  357,  291,  354,  231,   38, 1312,  865,
     910, 1357,  143,  972, 1225, 1354,  328,  459, 1458,  945, 1075,  752, 1461, 1270,  564, 1207,
     198,  965, 1281,  962,    7, 1348,  832,  579, 1082,  249, 1085, 1342, 1467, 1144,  700, 1535,
    1298, 1301,  977, 1046, 1491,  852, 1360, 1431, 1322, 1325, 1001, 1070, 1515,  876, 1384, 1455,  /* state 20 */
     206,  973, 1289,  970,   15, 1356,  840,  587, 1074,  241, 1077, 1334, 1459, 1136,  692, 1527,
    1498, 1307,  729,  920, 1501,  796, 1182, 1247, 1316,  869,  935,  166,  803,  866, 1248,  353,
     902, 1349,  135,  964, 1217, 1346,  320,  451, 1466,  953, 1083,  760, 1469, 1278,  572, 1215,
    1398, 1457,  503,  560,  949,  946,  756,  179,  942, 1389,  175, 1004, 1257, 1386,  360,  491,  /* state 21 */
     440,   57,  831,  894,  955,  186,  124,  189,  230,  997, 1313,  994,   39, 1380,  864,  611,
    1226, 1229, 1163,  332, 1353, 1422,  968, 1039,  918, 1365,  151,  980, 1233, 1362,  336,  467,
    1220,  325,  259,  322,  199,    6, 1280,  833,   24, 1371,  863,  604,  409,  474,  798,  477,
    1426,  913, 1043,  720, 1429, 1238,  532, 1175, 1358, 1417,  463,  520,  909,  906,  716,  139,  /* state 22 */
    1050,  217, 1053, 1310, 1435, 1112,  668, 1503, 1094,  391, 1473,  768,  709,  900,  706,   67,
    1450,  937, 1067,  744, 1453, 1262,  556, 1199, 1266, 1269, 1203,  372, 1393, 1462, 1008, 1079,
    1444, 1127,  675, 1504,  549,  422,  546,  801, 1210, 1275, 1213,  316, 1145,  248, 1534, 1343,
    1490, 1299,  721,  912, 1493,  788, 1174, 1239, 1306, 1309,  985, 1054, 1499,  860, 1368, 1439,  /* state 23 */
    1102,  399, 1481,  776,  717,  908,  714,   75, 1350, 1409,  455,  512,  901,  898,  708,  131,
    1514, 1323,  745,  936, 1517,  812, 1198, 1263, 1508,  867, 1383, 1440,  805,  802,  486,  545,
    1202, 1267, 1205,  308, 1137,  240, 1526, 1335, 1274, 1277, 1211,  380, 1401, 1470, 1016, 1087,
};

/* The paper's 48-bit Hilbert key: 16 bits per axis; equal to
 * clvr_hilbert3_bits(x, y, z, 16), computed with the state table from the
 * Morton code m = clvr_morton3(x, y, z): 8 dependent table steps, fully
 * unrolled on the device. */
CLVR_FORCE_INLINE clvr_u64 clvr_hilbert3_from_morton(clvr_u64 m)
{
    clvr_u64 key = 0;
    clvr_u32 state = 0;
    CLVR_UNROLL
    for (int shift = 3 * CLVR_SFC_BITS - 6; shift >= 0; shift -= 6) {
        const clvr_u32 e = clvr_hilbert3_table[state * 64u + (clvr_u32)((m >> shift) & 63u)];
        key = (key << 6) | (e & 63u);
        state = e >> 6;
    }
    return key;
}

/* The same for two Morton codes at once, the two table chains interleaved
 * step by step. One chain is 8 dependent loads that a CPU core cannot
 * overlap with the next element's (the box loads in between fill its
 * reorder window); two independent chains side by side halve the stall
 * (one thread, 10M hex keys: about 0.30 -> 0.24 s). */
CLVR_FORCE_INLINE void clvr_hilbert3_from_morton2(clvr_u64 m0, clvr_u64 m1, clvr_u64 *h0, clvr_u64 *h1)
{
    clvr_u64 k0 = 0, k1 = 0;
    clvr_u32 s0 = 0, s1 = 0;
    CLVR_UNROLL
    for (int shift = 3 * CLVR_SFC_BITS - 6; shift >= 0; shift -= 6) {
        const clvr_u32 e0 = clvr_hilbert3_table[s0 * 64u + (clvr_u32)((m0 >> shift) & 63u)];
        const clvr_u32 e1 = clvr_hilbert3_table[s1 * 64u + (clvr_u32)((m1 >> shift) & 63u)];
        k0 = (k0 << 6) | (e0 & 63u);
        k1 = (k1 << 6) | (e1 & 63u);
        s0 = e0 >> 6;
        s1 = e1 >> 6;
    }
    *h0 = k0;
    *h1 = k1;
}

CLVR_INLINE clvr_u64 clvr_hilbert3(clvr_u32 x, clvr_u32 y, clvr_u32 z)
{
    return clvr_hilbert3_from_morton(clvr_morton3(x, y, z));
}

/* Inverse of clvr_hilbert3_bits (Skilling's TransposetoAxes): writes the
 * cell of key h into xyz[0..2]. Used by tests to check bijection and
 * adjacency. */
CLVR_INLINE void clvr_hilbert3_decode(clvr_u64 h, clvr_u32 bits, clvr_u32 *xyz)
{
    clvr_u32 X0 = clvr_sfc_compact3(h >> 2), X1 = clvr_sfc_compact3(h >> 1), X2 = clvr_sfc_compact3(h), t;
    const clvr_u32 N = 2u << (bits - 1u);
    /* Gray decode by H ^ (H/2). */
    t = X2 >> 1;
    X2 ^= X1;
    X1 ^= X0;
    X0 ^= t;
    /* Undo excess work. */
    for (clvr_u32 Q = 2u; Q != N; Q <<= 1) {
        const clvr_u32 P = Q - 1u;
        if (X2 & Q) X0 ^= P;
        else { t = (X0 ^ X2) & P; X0 ^= t; X2 ^= t; }
        if (X1 & Q) X0 ^= P;
        else { t = (X0 ^ X1) & P; X0 ^= t; X1 ^= t; }
        if (X0 & Q) X0 ^= P;
    }
    xyz[0] = X0;
    xyz[1] = X1;
    xyz[2] = X2;
}

#endif /* CLVR_SFC_H */
