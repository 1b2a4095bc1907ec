// The little the dashboard's modules use of what is not theirs, hand-written for the type
// check (tsconfig.json): the vendored plotly.js (static/vendor/plotly-gl3d.min.js, a global
// script: window.Plotly) and the installed rerun-sdk's web viewer (/viewer/re_viewer.js, a
// global script: wasm_bindgen), and what the pages put on window.

/** plotly.js: the two calls the dashboard makes. */
interface PlotlyStatic {
  react(el: HTMLElement, data: object[], layout?: object, config?: object): Promise<HTMLElement>;
  purge(el: HTMLElement): void;
}

/** A click on a plot: the points under the pointer (with the customdata of their trace). */
interface PlotlyClickEvent {
  points?: Array<{ customdata?: unknown }>;
}

/** An element plotly.js has drawn a plot in: it adds the plot's data and its events. */
interface PlotlyHTMLElement extends HTMLElement {
  data?: unknown[];
  on(event: "plotly_click", handler: (ev: PlotlyClickEvent) => void): void;
  removeAllListeners?(event: string): void;
}

/** The Rerun web viewer's handle (rerun-sdk's re_viewer.js): the calls viewer_page.js makes. */
interface RerunWebHandle {
  start(canvas: HTMLElement | null): Promise<void>;
  open_channel(id: string, name: string): void;
  close_channel(id: string): void;
  send_rrd_to_channel(id: string, data: Uint8Array): void;
  has_panicked(): boolean;
  panic_message(): string;
}

/** rerun-sdk's re_viewer.js: loads the viewer's WebAssembly. */
declare function wasm_bindgen(module: Response): Promise<unknown>;
declare namespace wasm_bindgen {
  class WebHandle implements RerunWebHandle {
    constructor(options: Record<string, unknown>);
    start(canvas: HTMLElement | null): Promise<void>;
    open_channel(id: string, name: string): void;
    close_channel(id: string): void;
    send_rrd_to_channel(id: string, data: Uint8Array): void;
    has_panicked(): boolean;
    panic_message(): string;
  }
}

interface Window {
  /** plotly.js (index.html loads it before the modules). */
  Plotly: PlotlyStatic;
  /** The viewer page (viewer_page.js): open a recording's bytes as `name`. */
  legoptOpen?: (bytes: ArrayBuffer | Uint8Array, name?: string) => void;
  /** The viewer page: the URLs of other origins its fetch refused (the browser tests read it). */
  legoptRefused?: string[];
  /** The viewer page: the running viewer's handle. */
  _handle?: RerunWebHandle;
}
