#include "lsqt/util.h"

/* CRC-32 (IEEE, reflected 0xEDB88320), four bytes a step through four tables ("slicing
 * by 4"): an LSS is megabytes of histograms, and the bitwise form took 7 % of a short run. */
static uint32_t crc_tab[4][256];

static void crc_tables(void)
{
    for (uint32_t b = 0; b < 256; b++) {
        uint32_t c = b;
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
        crc_tab[0][b] = c;
    }
    for (int t = 1; t < 4; t++)
        for (int b = 0; b < 256; b++) crc_tab[t][b] = (crc_tab[t - 1][b] >> 8) ^ crc_tab[0][crc_tab[t - 1][b] & 0xFFu];
}

uint32_t lsqt_crc32(uint32_t crc, const void *data, size_t len)
{
    if (crc_tab[0][1] == 0) crc_tables(); /* the host calls this from one thread */
    const unsigned char *p = data;
    crc = ~crc;
    for (; len >= 4; len -= 4, p += 4) {
        crc ^= (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
        crc = crc_tab[3][crc & 0xFFu] ^ crc_tab[2][(crc >> 8) & 0xFFu] ^ crc_tab[1][(crc >> 16) & 0xFFu] ^
              crc_tab[0][crc >> 24];
    }
    for (; len > 0; len--, p++) crc = (crc >> 8) ^ crc_tab[0][(crc ^ *p) & 0xFFu];
    return ~crc;
}
