// Trees (§9.7) a stranger can write: the work bound and IN leaves reached by one split twice.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readPln } from '../src/node.mjs';
import { file4, common, varint, varints, outcome } from './files.mjs';

/** A version 4.1 file of one tree over the planes x ≤ 1 then the cube's other five (ν, φ, h). @param {number[]} tokens */
function treeFile(tokens) {
  const planes = [[Math.PI / 2, 0, 1], [Math.PI / 2, Math.PI, 1], [Math.PI / 2, Math.PI / 2, 1],
    [Math.PI / 2, 1.5 * Math.PI, 1], [0, 0, 1], [Math.PI, 0, 1]];
  const body = [...common([0, 1, 2, 3, 4, 5]), ...varint(tokens.length), ...varints(tokens)];
  return file4({ planes: planes.flat(), version: [4, 1], groups: [{ kind: 2, body, method: 1 }] });
}

test('a chain of 200,000 splits is refused with LIMIT_EXCEEDED before any clip (issue 49 item 3)', () => {
  const n = 200_000;
  const tokens = [...new Array(n).fill(2), 0, ...new Array(n).fill(1)];
  assert.equal(outcome(treeFile(tokens), readPln, { decode: true }), 'LIMIT_EXCEEDED');
});

test('a cube as a chain of its six splits stays within the bound and decodes', () => {
  assert.equal(outcome(treeFile([2, 3, 4, 5, 6, 7, 0, 1, 1, 1, 1, 1, 1]), readPln, { decode: true }), 'ok');
});

test('an IN leaf behind one split taken twice is UNBOUNDED_POLYTOPE', () => {
  assert.equal(outcome(treeFile([2, 2, 0, 1, 1]), readPln, { decode: true }), 'UNBOUNDED_POLYTOPE');
});
