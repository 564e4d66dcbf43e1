// The look the page and `hairsim run --out`'s pictures share (std-harness/src/picture: the
// same colours and the same brightness per strand).

export const PALETTE = {
  background: [21, 23, 28],
  root: [58, 32, 18],
  tip: [222, 168, 84],
  collider: [150, 160, 176],
  warning: [255, 64, 96],
  held: [102, 204, 255],
  // Toward the light, from the hair: above, in front, to the right (world Y up).
  light: [0.45, 0.8, 0.4],
};

const MASK = (1n << 64n) - 1n;

// A brightness factor in 0.85 ..= 1.15 fixed by a strand's index (SplitMix64's finaliser, as
// the native pictures' `strand_tint`).
export function strandTint(index) {
  let z = (BigInt(index) + 0x9e3779b97f4a7c15n) & MASK;
  z = ((z ^ (z >> 30n)) * 0xbf58476d1ce4e5b9n) & MASK;
  z = ((z ^ (z >> 27n)) * 0x94d049bb133111ebn) & MASK;
  z ^= z >> 31n;
  return 0.85 + 0.3 * (Number(z >> 40n) / 2 ** 24);
}
