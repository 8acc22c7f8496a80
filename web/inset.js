// Inset frames (docs/protocol.md, "Inset frames"): the server sends a downscaled whole frame
// and a full-resolution square around the gaze (two images, or with H.264 one picture holding
// both); this composes them into one image. CPU twin:
// `compose` in src/encode/inset.rs (bilinear upscale, the inset's sides feathered by linear
// ramps whose product is its weight; sides on the frame's edge are not feathered).

// The inset's weight as an alpha mask along one axis: 0 at a feathered side, 1 `feather` of
// the length in.
function ramp(ctx, length, across, horizontal, featherStart, featherEnd, feather) {
  const g = horizontal ? ctx.createLinearGradient(0, 0, length, 0) : ctx.createLinearGradient(0, 0, 0, length);
  g.addColorStop(0, featherStart ? 'rgba(0,0,0,0)' : '#000');
  g.addColorStop(feather, '#000');
  g.addColorStop(1 - feather, '#000');
  g.addColorStop(1, featherEnd ? 'rgba(0,0,0,0)' : '#000');
  ctx.fillStyle = g;
  if (horizontal) ctx.fillRect(0, 0, length, across); else ctx.fillRect(0, 0, across, length);
}

// Decodes both images of an inset frame (`bytes`: what follows the header) and returns the
// composed frame as an ImageBitmap.
export async function composeInset(header, bytes, type) {
  const i = header.inset;
  const split = bytes.byteLength - i.inset_bytes;
  const [base, inset] = await Promise.all([
    createImageBitmap(new Blob([bytes.subarray(0, split)], { type })),
    createImageBitmap(new Blob([bytes.subarray(split)], { type })),
  ]);
  try {
    return compose(header, base, [0, 0, i.base_width, i.base_height], inset, [0, 0, i.width, i.height]);
  } finally {
    base.close();
    inset.close();
  }
}

// An H.264 inset frame: both parts lie in one decoded picture (`header.inset.packed`); the
// caller closes `picture`.
export function composePacked(header, picture) {
  const i = header.inset;
  return compose(header, picture, [0, 0, i.base_width, i.base_height],
    picture, [i.packed.inset_x, 0, i.width, i.height]);
}

// The base's rectangle of `base` scaled up to the frame, the inset's rectangle of `inset`
// drawn over it, feathered; returns an ImageBitmap.
function compose(header, base, [bx, by, bw, bh], inset, [ix, iy, iw, ih]) {
  const i = header.inset;
  const out = new OffscreenCanvas(header.width, header.height);
  const ctx = out.getContext('2d');
  ctx.imageSmoothingEnabled = true;
  ctx.drawImage(base, bx, by, bw, bh, 0, 0, header.width, header.height);
  const tile = new OffscreenCanvas(i.width, i.height);
  const t = tile.getContext('2d');
  t.drawImage(inset, ix, iy, iw, ih, 0, 0, i.width, i.height);
  t.globalCompositeOperation = 'destination-in';
  ramp(t, i.width, i.height, true, i.x > 0, i.x + i.width < header.width, i.feather);
  ramp(t, i.height, i.width, false, i.y > 0, i.y + i.height < header.height, i.feather);
  ctx.drawImage(tile, i.x, i.y);
  return out.transferToImageBitmap();
}
