/** Errors of spec/pln.md §12.2: one exception class whose `code` is the catalogue's code. */

export class PlnError extends Error {
  /**
   * @param {string} code the §12.2 code, e.g. "BAD_PAYLOAD"
   * @param {string} [detail] what was wrong, for people
   */
  constructor(code, detail = '') {
    super(detail ? `${code}: ${detail}` : code);
    this.name = 'PlnError';
    /** @type {string} */
    this.code = code;
    /** @type {string|null} chunk type tag where the error was found, set by the chunk loop */
    this.chunk = null;
    /** @type {number|null} offset of that chunk's first byte */
    this.offset = null;
    /** @type {{tag: number, offset: number} | null} version 6: the record of the chunk's body segment, its tag and its offset in the segment's raw bytes */
    this.record = null;
  }
}

/**
 * Throw a PlnError; a function so that checks read as one line.
 * @param {string} code
 * @param {string} [detail]
 * @returns {never}
 */
export function fail(code, detail) {
  throw new PlnError(code, detail);
}
