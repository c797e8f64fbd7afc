// Marginal geometry (§9.4's relative criteria), decided as planefmt decides it (issue 49 item 8).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { intersectHalfSpaces } from '../src/convex.mjs';

const NORMALS = [[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];

/** @param {number[][]} normals @param {number[]} h */
function outcome(normals, h) {
  const planes = Float64Array.from(normals.flatMap((n, i) => [...n, h[i]]));
  try {
    const poly = intersectHalfSpaces(planes, normals.length, { left: 1e8 });
    return `${new Set(poly.faces.flatMap((f) => [...f.loop])).size} vertices`;
  } catch (err) {
    return /** @type {{code: string}} */ (err).code;
  }
}

for (const side of [7e-102, 1e-30, 1, 1e30, 3e200]) {
  test(`a cube of side ${side} decodes`, () => assert.equal(outcome(NORMALS, new Array(6).fill(side / 2)), '8 vertices'));
}

test('a cube missing a plane that float32 tilt closes 2.3e7 away is UNBOUNDED_POLYTOPE', () => {
  const f = (/** @type {number} */ a) => Math.fround(a);
  const normals = [[0, 0], [Math.PI / 2, 0], [Math.PI, 0], [1.5 * Math.PI, 0]].map(([phi]) => {
    const nu = f(Math.PI / 2);
    return [Math.sin(nu) * Math.cos(f(phi)), Math.sin(nu) * Math.sin(f(phi)), Math.cos(nu)];
  });
  assert.equal(outcome([...normals, [0, 0, 1]], [1, 1, 1, 1, 1]), 'UNBOUNDED_POLYTOPE');
});

for (const [thickness, want] of [[1e-9, 'EMPTY_POLYTOPE'], [1e-8, 'EMPTY_POLYTOPE'], [8.7e-8, '8 vertices'], [1e-6, '8 vertices']]) {
  for (const offset of [0, 1000]) {
    test(`a slab ${thickness} thick at ${offset} from the origin: ${want}`, () => {
      const h = [thickness, 1, 0, 0, 1, 0].map((v, i) => v + offset * NORMALS[i].reduce((s, c) => s + c, 0));
      assert.equal(outcome(NORMALS, h), want);
    });
  }
}
