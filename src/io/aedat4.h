/* iniVation's AEDAT 4.0 (DV, dv-processing), what its writer (aedat4_writer.c) and reader
 * (aedat4_read.c) share. The file:
 *
 *   "#!AER-DAT4.0\r\n"
 *   the IOHeader: a size-prefixed FlatBuffer (identifier "IOHE"): compression, dataTablePosition
 *     (the FileDataTable's byte offset, -1: none) and infoNode (XML naming each stream: its id,
 *     typeIdentifier "EVTS" for events, and for events the sensor's sizeX and sizeY)
 *   packets: a PacketHeader (int32 stream id, int32 size) and size bytes: one LZ4 or ZSTD frame
 *     (or the bytes as they are for compression NONE) holding a size-prefixed FlatBuffer whose
 *     identifier names its type; events: an EventPacket ("EVTS"), a vector of Event structs
 *     (int64 t in us, int16 x, int16 y, bool on; 16 bytes with padding)
 *   the FileDataTable at dataTablePosition: compressed like a packet but with no PacketHeader, a
 *     size-prefixed FlatBuffer ("FTAB"), one FileDataDefinition per packet (its data's byte
 *     offset, PacketHeader, element count, first and last timestamp), so readers can seek.
 *
 * FlatBuffers are little-endian; offsets (uoffset) are unsigned 32-bit and point forward from
 * where they are stored; a table starts with a signed 32-bit offset back to its vtable (the
 * vtable is at the table's position minus that value), and the vtable lists, as 16-bit values,
 * its own size, the table's size and each field's offset in the table (0: absent, the default).
 * Scalars are aligned to their size counted from the start of the size-prefixed buffer. */
#ifndef EVR_IO_AEDAT4_H
#define EVR_IO_AEDAT4_H

#define EVR_AEDAT4_VERSION "#!AER-DAT4.0\r\n"
#define EVR_AEDAT4_VERSION_LEN 14

/* IOHeader.compression */
enum {
    EVR_AEDAT4_NONE = 0,
    EVR_AEDAT4_LZ4 = 1,
    EVR_AEDAT4_LZ4_HIGH = 2,
    EVR_AEDAT4_ZSTD = 3,
    EVR_AEDAT4_ZSTD_HIGH = 4
};

/* Event struct in an EventPacket: t at 0, x at 8, y at 10, on at 12, 3 bytes of padding */
#define EVR_AEDAT4_EVENT_BYTES 16
/* x and y are int16 */
#define EVR_AEDAT4_MAX_XY 32768

#endif
