/** CRC-32/ISO-HDLC (spec §4.1), the CRC of PNG and zlib, table-driven. */

const TABLE = new Uint32Array(256);
for (let n = 0; n < 256; n++) {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  TABLE[n] = c >>> 0;
}

/**
 * CRC of bytes[start, end), continuing `crc`, the CRC of the bytes before them.
 * @param {Uint8Array} bytes
 * @param {number} start
 * @param {number} end
 * @param {number} [crc]
 * @returns {number} unsigned 32-bit
 */
export function crc32(bytes, start, end, crc = 0) {
  let c = (crc ^ 0xffffffff) >>> 0;
  for (let i = start; i < end; i++) c = TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}
