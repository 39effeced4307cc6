/* preprocess.cl: the one program of the preprocessing stages (one build,
 * every kernel): bounds and keys, scan and select, radix sort, gather and
 * clusters, instance split and re-indexing. Each stage file also builds on
 * its own (tests build sort.cl and scan.cl alone). */
#include "clvr_shared.h"
#include "bounds.cl"
#include "scan.cl"
#include "sort.cl"
#include "cluster.cl"
#include "reindex.cl"
