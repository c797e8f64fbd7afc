/**
 * The decode budget (spec §12.4): the vertices and triangles one decode of a file may produce, its
 * groups of every object in all, a copy (kind 11) counting its source's again. A group that declares
 * its counts (sealed, shells, shell trees and walks: kinds 5 to 10, 12, 13) is charged as they are
 * read, before anything of their size is allocated; any other once decoded.
 */
import { fail } from './errors.mjs';

/** Kinds whose kind data declares the vertices and triangles they decode to. */
export const DECLARED_KINDS = new Set([5, 6, 7, 8, 9, 10, 12, 13]);

export class Budget {
  /** @param {{vertices: number, triangles: number}} limits */
  constructor(limits) {
    this.limits = limits;
    this.vertices = 0;
    this.triangles = 0;
  }

  /**
   * Adds group `group`'s output, or throws LIMIT_EXCEEDED (vertices checked first) without adding it.
   * @param {number} group @param {number} vertices @param {number} triangles
   */
  charge(group, vertices, triangles) {
    for (const [what, have, more, limit] of /** @type {[string, number, number, number][]} */ ([
      ['vertices', this.vertices, vertices, this.limits.vertices],
      ['triangles', this.triangles, triangles, this.limits.triangles],
    ])) {
      if (have + more > limit) {
        fail('LIMIT_EXCEEDED', `group ${group}: its ${more} ${what} bring the file's output to ${have + more}, above this `
          + `reader's limit of ${limit} ${what} (raise it with the option limits: {${what}: N}, or --max-${what} N)`);
      }
    }
    this.vertices += vertices;
    this.triangles += triangles;
  }

  /**
   * charge bound to `group`, for the kind readers, which know no group index.
   * @param {number} group @returns {Charge}
   */
  of(group) {
    return (vertices, triangles) => this.charge(group, vertices, triangles);
  }
}

/** @typedef {(vertices: number, triangles: number) => void} Charge */

/** The charge of a caller without a budget: nothing. @type {Charge} */
export const NO_CHARGE = () => {};
