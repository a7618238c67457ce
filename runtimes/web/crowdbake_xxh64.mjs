// crowdbake_xxh64.mjs - XXH64 (seed 0), the .pal checksum, from the algorithm's specification.
// An ES module with no dependencies (crowdbake_pal.mjs re-exports xxh64). Public domain / MIT-0.

// On 32-bit halves (hi, lo): BigInt arithmetic allocates per operation and hashes at about 1 MB/s.

const P1H = 0x9e3779b1, P1L = 0x85ebca87, P2H = 0xc2b2ae3d, P2L = 0x27d4eb4f, P3H = 0x165667b1, P3L = 0x9e3779f9;
const P4H = 0x85ebca77, P4L = 0xc2b2ae63, P5H = 0x27d4eb2f, P5L = 0x165667c5;

// XXH64 of `parts`, an array of Uint8Arrays hashed as if concatenated (the checksum hashes the
// file with its checksum field read as zero without copying the file). Returns a BigInt.
export function xxh64(parts) {
    if (parts instanceof Uint8Array) parts = [parts];
    let rh = 0, rl = 0; // the result register of the helpers below
    const mul = (ah, al, bh, bl) => { // low 64 bits of a * b
        const a0 = al & 0xffff, a1 = al >>> 16, b0 = bl & 0xffff, b1 = bl >>> 16;
        const p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0;
        const mid = (p00 >>> 16) + (p01 & 0xffff) + (p10 & 0xffff);
        rl = (((mid & 0xffff) << 16) | (p00 & 0xffff)) >>> 0;
        const carry = a1 * b1 + (p01 >>> 16) + (p10 >>> 16) + (mid >>> 16);
        rh = (carry + Math.imul(al, bh) + Math.imul(ah, bl)) >>> 0;
    };
    const add = (ah, al, bh, bl) => {
        const lo = al + bl;
        rl = lo >>> 0;
        rh = (ah + bh + (lo > 0xffffffff ? 1 : 0)) >>> 0;
    };
    const rotl = (h, l, r) => { // 0 < r < 32
        rh = ((h << r) | (l >>> (32 - r))) >>> 0;
        rl = ((l << r) | (h >>> (32 - r))) >>> 0;
    };
    const round = (ah, al, ih, il) => { // rotl(acc + input * P2, 31) * P1
        mul(ih, il, P2H, P2L);
        add(ah, al, rh, rl);
        rotl(rh, rl, 31);
        mul(rh, rl, P1H, P1L);
    };
    let total = 0;
    for (const p of parts) total += p.length;
    const v = new Uint32Array([0x60ea27ee, 0xadc0b5d6, P2H, P2L, 0, 0, 0x61c8864e, 0x7a143579]); // P1+P2, P2, 0, -P1
    const consume = (view, o) => {
        for (let k = 0; k < 4; ++k) {
            round(v[2 * k], v[2 * k + 1], view.getUint32(o + 8 * k + 4, true), view.getUint32(o + 8 * k, true));
            v[2 * k] = rh, v[2 * k + 1] = rl;
        }
    };
    const stripe = new Uint8Array(32); // carries bytes across part boundaries
    const stripeView = new DataView(stripe.buffer);
    let buffered = 0;
    for (const p of parts) {
        const view = new DataView(p.buffer, p.byteOffset, p.byteLength);
        let i = 0;
        if (buffered) {
            const take = Math.min(32 - buffered, p.length);
            stripe.set(p.subarray(0, take), buffered);
            buffered += take, i = take;
            if (buffered < 32) continue;
            consume(stripeView, 0);
            buffered = 0;
        }
        for (; i + 32 <= p.length; i += 32) consume(view, i);
        stripe.set(p.subarray(i), 0);
        buffered = p.length - i;
    }
    let hh, hl;
    if (total >= 32) {
        rotl(v[0], v[1], 1); hh = rh, hl = rl;
        for (const [k, r] of [[1, 7], [2, 12], [3, 18]]) {
            const sh = hh, sl = hl;
            rotl(v[2 * k], v[2 * k + 1], r);
            add(sh, sl, rh, rl); hh = rh, hl = rl;
        }
        for (let k = 0; k < 4; ++k) { // h = (h ^ round(0, v_k)) * P1 + P4
            round(0, 0, v[2 * k], v[2 * k + 1]);
            mul((hh ^ rh) >>> 0, (hl ^ rl) >>> 0, P1H, P1L);
            add(rh, rl, P4H, P4L); hh = rh, hl = rl;
        }
    } else {
        hh = P5H, hl = P5L;
    }
    add(hh, hl, Math.floor(total / 0x100000000), total >>> 0); hh = rh, hl = rl;
    let o = 0;
    for (; o + 8 <= buffered; o += 8) { // h = rotl(h ^ round(0, lane), 27) * P1 + P4
        round(0, 0, stripeView.getUint32(o + 4, true), stripeView.getUint32(o, true));
        rotl((hh ^ rh) >>> 0, (hl ^ rl) >>> 0, 27);
        mul(rh, rl, P1H, P1L);
        add(rh, rl, P4H, P4L); hh = rh, hl = rl;
    }
    if (o + 4 <= buffered) { // h = rotl(h ^ (u32 * P1), 23) * P2 + P3
        mul(0, stripeView.getUint32(o, true), P1H, P1L);
        rotl((hh ^ rh) >>> 0, (hl ^ rl) >>> 0, 23);
        mul(rh, rl, P2H, P2L);
        add(rh, rl, P3H, P3L); hh = rh, hl = rl;
        o += 4;
    }
    for (; o < buffered; ++o) { // h = rotl(h ^ (byte * P5), 11) * P1
        mul(0, stripe[o], P5H, P5L);
        rotl((hh ^ rh) >>> 0, (hl ^ rl) >>> 0, 11);
        mul(rh, rl, P1H, P1L); hh = rh, hl = rl;
    }
    hl = (hl ^ (hh >>> 1)) >>> 0; // h ^= h >> 33
    mul(hh, hl, P2H, P2L); hh = rh, hl = rl;
    hl = (hl ^ ((hl >>> 29) | (hh << 3))) >>> 0, hh = (hh ^ (hh >>> 29)) >>> 0; // h ^= h >> 29
    mul(hh, hl, P3H, P3L); hh = rh, hl = rl;
    hl = (hl ^ hh) >>> 0; // h ^= h >> 32
    return (BigInt(hh) << 32n) | BigInt(hl);
}
