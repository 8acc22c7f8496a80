// Inset frames (docs/protocol.md, "Inset frames"): the server sends a downscaled whole frame
// and a full-resolution square around the gaze; this composes them into one image. CPU twin:
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
    const out = new OffscreenCanvas(header.width, header.height);
    const ctx = out.getContext('2d');
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(base, 0, 0, header.width, header.height);
    const tile = new OffscreenCanvas(i.width, i.height);
    const t = tile.getContext('2d');
    t.drawImage(inset, 0, 0);
    t.globalCompositeOperation = 'destination-in';
    ramp(t, i.width, i.height, true, i.x > 0, i.x + i.width < header.width, i.feather);
    ramp(t, i.height, i.width, false, i.y > 0, i.y + i.height < header.height, i.feather);
    ctx.drawImage(tile, i.x, i.y);
    return out.transferToImageBitmap();
  } finally {
    base.close();
    inset.close();
  }
}
