/* libFuzzer target: the LSS reader must refuse or accept any bytes without crashing. */
#include <stddef.h>
#include <stdint.h>

#include "lsqt/lss.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    lsqt_state st;
    char err[512];
    if (lsqt_lss_parse(data, size, &st, err, sizeof err) == 0) lsqt_state_free(&st);
    return 0;
}
