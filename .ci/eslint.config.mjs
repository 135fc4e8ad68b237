// ESLint for report.html's scripts (cellengine/report/assets), run by `make lint`, which
// installs eslint and globals under .venv/eslint and passes this file with --config.
import { createRequire } from 'node:module';

// Resolve the packages next to the eslint that runs this file (.venv/eslint/node_modules), not
// next to this file: nothing is installed in the repository's own folders.
const require = createRequire(process.argv[1]);
const js = require('@eslint/js');
const globals = require('globals');

export default [
  js.configs.recommended,
  {
    files: ['cellengine/report/assets/**/*.js'],
    languageOptions: {
      ecmaVersion: 2022,
      sourceType: 'script',
      parserOptions: { ecmaFeatures: { impliedStrict: true } },
      globals: globals.browser,
    },
  },
];
