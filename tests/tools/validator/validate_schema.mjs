// validate_schema.mjs SCHEMA FILE...: validates JSON files against a JSON Schema (draft 2020-12)
// with ajv; prints a line per file and exits 1 if any is invalid.
import { readFileSync } from 'node:fs';
import Ajv2020 from 'ajv/dist/2020.js';

const [schemaPath, ...files] = process.argv.slice(2);
const validate = new Ajv2020({ allErrors: true, strict: false }).compile(JSON.parse(readFileSync(schemaPath, 'utf8')));
let failed = false;
for (const f of files) {
  const ok = validate(JSON.parse(readFileSync(f, 'utf8')));
  console.log(`${f}: ${ok ? 'valid' : 'INVALID ' + JSON.stringify(validate.errors.slice(0, 5))}`);
  if (!ok) failed = true;
}
process.exit(failed ? 1 : 0);
