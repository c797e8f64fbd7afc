/** A decoded scene as Wavefront OBJ text: one `o` per object, world coordinates. */

/** @param {ReturnType<typeof import('./index.mjs').readPln>} file */
export function toObj(file) {
  const { positions64: p, indices: ix, groupOfTriangle } = file.mesh();
  const lines = ['# decoded from .pln by planefmt-js'];
  for (let v = 0; v < p.length; v += 3) lines.push(`v ${p[v]} ${p[v + 1]} ${p[v + 2]}`);
  let group = -1;
  for (let t = 0; t < ix.length; t += 3) {
    if (groupOfTriangle[t / 3] !== group) {
      group = groupOfTriangle[t / 3];
      lines.push(`g group${group}`);
    }
    lines.push(`f ${ix[t] + 1} ${ix[t + 1] + 1} ${ix[t + 2] + 1}`);
  }
  return `${lines.join('\n')}\n`;
}
