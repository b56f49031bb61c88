/* Room on the file system claimed before a library writes into it: a write that fails midway
 * (a full disk) can leave a library's own state inconsistent (HDF5 then loses a chunk from a
 * dataset's chunk index though its later write succeeds), so the room is claimed first and a
 * full disk is met before the library writes anything. */
#ifndef EVR_IO_FILE_ROOM_H
#define EVR_IO_FILE_ROOM_H

#include <stdint.h>

/* Claims the blocks of bytes [from, from + len) of the open file fd without changing its size
 * (Linux fallocate, FALLOC_FL_KEEP_SIZE), so that writes within them cannot fail for want of
 * space. 0 when claimed, or when the file system or system cannot claim room ahead (nothing is
 * guaranteed then, nothing is lost); -1 with errno set (ENOSPC, EFBIG, EIO, EDQUOT) when there is
 * no room. */
int evr_file_claim(int fd, uint64_t from, uint64_t len);

/* Frees what was claimed past the end of the open file fd (opened for writing): a truncation to
 * its own size, which file systems take as the way to drop blocks kept past the end. Failing
 * changes nothing but the space the file holds, so it is not reported. */
void evr_file_unclaim_tail(int fd);

#endif
