/* Proves the status table: names, exit codes and formatted messages. */
#include "status.h"
#include "test_util.h"

int main(void)
{
    clvr_error err = {0};
    TU_CHECK(strcmp(clvr_status_name(CLVR_ERR_TRUNCATED), "ERR_TRUNCATED") == 0);
    TU_CHECK_EQ_U64(clvr_status_exit_code(CLVR_OK), 0);
    TU_CHECK_EQ_U64(clvr_status_exit_code(CLVR_ERR_USAGE), 2);
    TU_CHECK_EQ_U64(clvr_status_exit_code(CLVR_ERR_BAD_INDEX), 3);
    TU_CHECK_EQ_U64(clvr_status_exit_code(CLVR_ERR_NO_DEVICE), 4);
    TU_CHECK_EQ_U64(clvr_status_exit_code(CLVR_ERR_WRITE), 5);
    TU_CHECK(clvr_error_set(&err, CLVR_ERR_IO, "%s: %d", "x.bin", 7) == CLVR_ERR_IO);
    TU_CHECK(err.status == CLVR_ERR_IO && strcmp(err.msg, "x.bin: 7") == 0);
    /* Quoted file contents cannot break the one-line contract... */
    clvr_error_set(&err, CLVR_ERR_BAD_FIELD, "f.umesh: attribute '%s' is bad", "a\nb\x1b[31m");
    TU_CHECK(strcmp(err.msg, "f.umesh: attribute 'a?b?[31m' is bad") == 0);
    /* ...but a kernel build failure keeps the compiler log's lines. */
    clvr_error_set(&err, CLVR_ERR_KERNEL_BUILD, "build failed:\n%s", "x.cl:1:2: error\n");
    TU_CHECK(strcmp(err.msg, "build failed:\nx.cl:1:2: error\n") == 0);
    for (int s = 0; s < CLVR_STATUS_COUNT; ++s) TU_CHECK(strlen(clvr_status_text((clvr_status)s)) > 0);
    return tu_finish("test_status");
}
