// The web reader's fuzz findings (tests/fuzz/regressions/web, from `make fuzz`), replayed with the
// checks the fuzzer makes (tests/fuzz/web/web_reader_target.mjs): each input ends in a value a
// runtime can use or in one named Error, never a RangeError, a TypeError or a hang.
import { test } from 'node:test';
import { readdirSync, readFileSync } from 'node:fs';
import path from 'node:path';
import { checkInput } from '../../../tests/fuzz/web/web_reader_target.mjs';
import { fzstd } from './support.mjs';

const dir = 'tests/fuzz/regressions/web';
const inputs = readdirSync(dir).filter((n) => !n.startsWith('.'));

test('there are regression inputs to replay', () => {
    if (inputs.length === 0) throw new Error(`${dir}: no inputs: a replay that checks nothing is a failure`);
});

for (const name of inputs)
    test(`replay ${name}`, () => checkInput(readFileSync(path.join(dir, name)), fzstd));
