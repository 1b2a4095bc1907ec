// ESLint (flat config) of the dashboard's own modules, services/web/static/js: the
// recommended rules for browser ES modules. The vendored libraries (static/vendor: plotly.js,
// Swagger UI) and any minified file are not ours and are not linted.
// Run: services/web/check_frontend.sh (or npx eslint services/web/static/js).
import js from "@eslint/js";
import globals from "globals";

const STRICTER = {
  "no-unused-vars": ["error", { argsIgnorePattern: "^_", caughtErrorsIgnorePattern: "^_", varsIgnorePattern: "^_" }],
  eqeqeq: ["error", "smart"],
  "no-var": "error",
  "prefer-const": "error",
};

export default [
  { ignores: ["node_modules/**", "services/web/static/vendor/**", "**/*.min.js", "**/*.d.ts"] },
  {
    files: ["services/web/static/js/**/*.js"],
    languageOptions: { ecmaVersion: 2022, sourceType: "module", globals: { ...globals.browser } },
    rules: { ...js.configs.recommended.rules, ...STRICTER },
  },
  {
    // the Rerun viewer's page: a classic script (loaded before the viewer's own
    // /viewer/re_viewer.js, which defines wasm_bindgen)
    files: ["services/web/static/js/viewer_page.js"],
    languageOptions: { sourceType: "script", globals: { ...globals.browser, wasm_bindgen: "readonly" } },
  },
  {
    files: ["eslint.config.js"],
    languageOptions: { ecmaVersion: 2022, sourceType: "module" },
    rules: { ...js.configs.recommended.rules },
  },
];
