// Renders Foxglove Studio's `App` (put on `window` by @foxglove/studio-base's assets/index.js) the way its web
// build does, with what a test needs instead of the browser's storage: the layout given by the page's
// `layout` parameter (a URL on this server) as the one stored layout, selected through Studio's own
// `layoutId` deep-link parameter (a later `studioOpen` with another `layoutId` and `layout` adds that layout);
// every other parameter (ds, ds.url) is Studio's own deep link.
/* global App, initI18n, FoxgloveWebSocketDataSourceFactory, McapLocalDataSourceFactory, RemoteDataSourceFactory */
(async () => {
  const params = new URLSearchParams(window.location.search);
  const layoutId = params.get("layoutId");
  const layouts = new Map();
  const addLayout = async (id, url) => {
    const data = await (await fetch(url)).json();
    layouts.set(id, {
      id, name: id, permission: "CREATOR_WRITE",
      baseline: { data, savedAt: new Date().toISOString() }, working: undefined, syncInfo: undefined,
    });
  };
  if (layoutId && params.get("layout")) await addLayout(layoutId, params.get("layout"));
  const layoutStorage = {
    async list() { return [...layouts.values()]; },
    async get(_ns, id) { return layouts.get(id); },
    async put(_ns, layout) { layouts.set(layout.id, layout); return layout; },
    async delete(_ns, id) { layouts.delete(id); },
    async importLayouts() {},
    async migrateUnnamespacedLayouts() {},
  };
  const settings = new Map();
  const listeners = new Map();
  const appConfiguration = {
    get: (key) => settings.get(key),
    set: async (key, value) => { settings.set(key, value); for (const cb of listeners.get(key) ?? []) cb(value); },
    addChangeListener: (key, cb) => { listeners.set(key, [...(listeners.get(key) ?? []), cb]); },
    removeChangeListener: (key, cb) => { listeners.set(key, (listeners.get(key) ?? []).filter((c) => c !== cb)); },
  };
  await initI18n();
  const dataSources = [
    new FoxgloveWebSocketDataSourceFactory(), new McapLocalDataSourceFactory(), new RemoteDataSourceFactory(),
  ];
  const root = document.getElementById("root");
  const mount = () => ReactDOM.render(React.createElement(App, {
    deepLinks: [window.location.href], appConfiguration, dataSources, layoutStorage, extensionLoaders: [],
    enableGlobalCss: true,
  }), root);
  // Studio opened again on other deep-link parameters without reloading its 56 MB build: the page's URL set to
  // them, the app unmounted (its player closed) and mounted afresh, as on a page load
  window.studioOpen = async (search) => {
    const p = new URLSearchParams(search);
    if (p.get("layoutId") && p.get("layout") && !layouts.has(p.get("layoutId"))) {
      await addLayout(p.get("layoutId"), p.get("layout"));
    }
    window.history.replaceState(null, "", `${window.location.pathname}?${search}`);
    ReactDOM.unmountComponentAtNode(root);
    mount();
  };
  mount();
  window.hostReady = true;
})().catch((err) => { window.hostError = String(err && err.stack || err); console.error(err); });
