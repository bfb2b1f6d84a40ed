// partscale's browser editor: raymarched CSDF, draggable zone planes, live preview, apply/undo.
// This module only wires the parts: the store (state.ts), the scene (scene.ts), the panel (ui.ts),
// plane dragging (drag.ts), server commands (commands.ts) and the hooks for scripts (hooks.ts).
import { createCommands } from './commands';
import { bindDrag } from './drag';
import { exposeHooks } from './hooks';
import { createScene } from './scene';
import { createStore } from './state';
import { bindPanel, showPanel } from './ui';
import './style.css';

// ?canvas=WxH fixes the canvas's size; ?capture=1 keeps its pixels readable and times each frame
// to the GPU's end (tests and benchmarks; see SceneOptions)
const params = new URLSearchParams(location.search);
const size = params.get('canvas')?.match(/^(\d+)x(\d+)$/);
const store = createStore();
showPanel(store);
const scene = createScene(store, document.getElementById('view') as HTMLElement, {
  fixedSize: size ? [Number(size[1]), Number(size[2])] : null,
  capture: params.get('capture') === '1',
});
const commands = createCommands(store, scene);
bindPanel(store, commands);
bindDrag(store, scene, commands);
exposeHooks(store, scene);
commands.load().catch((e) =>
  store.dispatch({
    type: 'set-status',
    message: `loading failed: ${e instanceof Error ? e.message : String(e)}`,
    error: true,
  }),
);
