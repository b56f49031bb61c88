/* Little-endian loads and stores, for the binary formats evray writes and reads (Prophesee RAW
 * and DAT, ROS bags, NPY headers) whatever the host's byte order. */
#ifndef EVR_IO_BYTE_ORDER_H
#define EVR_IO_BYTE_ORDER_H

#include <stdint.h>

static inline void evr_put_le16(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v & 0xff);
    p[1] = (unsigned char)((v >> 8) & 0xff);
}
static inline void evr_put_le32(unsigned char *p, uint32_t v)
{
    evr_put_le16(p, v & 0xffff);
    evr_put_le16(p + 2, v >> 16);
}
static inline void evr_put_le64(unsigned char *p, uint64_t v)
{
    evr_put_le32(p, (uint32_t)v);
    evr_put_le32(p + 4, (uint32_t)(v >> 32));
}
static inline uint32_t evr_get_le16(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8;
}
static inline uint32_t evr_get_le32(const unsigned char *p)
{
    return evr_get_le16(p) | evr_get_le16(p + 2) << 16;
}

#endif
