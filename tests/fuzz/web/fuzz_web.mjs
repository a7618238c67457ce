// fuzz_web.mjs - Jazzer.js entry: the web reader (runtimes/web/crowdbake_pal.mjs) on arbitrary bytes, zstd
// payloads through fzstd as a page decodes them (make fuzz; what it checks: web_reader_target.mjs).
import { decompress } from '../../../runtimes/web/node_modules/fzstd/esm/index.mjs';
import { checkInput } from './web_reader_target.mjs';

const fzstd = (bytes, size) => decompress(bytes, new Uint8Array(size));

export function fuzz(data) {
    checkInput(data, fzstd);
}
