#include <stdio.h>
#include "cl_context.h"
int main(int argc, char **argv)
{
    (void)argc; (void)argv;
    clvr_error err = {0};
    if (clvr_cl_list_devices(stdout, &err) != CLVR_OK) { fprintf(stderr, "clvr: %s\n", err.msg); return 4; }
    return 0;
}
