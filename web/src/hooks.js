// window.vpmView: what the browser tests (tests/browser/) and the benchmark (bench/view/) read and
// drive. Nothing of the page depends on it.

export function testHooks(app) {
  const { scene, rowsView, painter, cohort, store, state, model, detail } = app;
  const all = app.rows.flatMap((r) => r.cells);
  const describe = (c, i) => ({ i, subject: c.subject.id, group: c.subject.group, kind: c.column.kind, feature: c.column.feature,
    column: c.column.label, rect: c.el.getBoundingClientRect().toJSON() });

  /** What cell `cell` shows now (its data loaded first), drawn at full resolution. */
  async function pixelsOf(cell) {
    if (cell.subject.kind !== 'reference') await cohort.load([cell.subject]);
    painter.prepare(cell);
    const shown = scene.visible([cell]);
    const px = scene.cellPixels(cell, shown);
    rowsView.requestRender();
    return px;
  }

  /** Turns every view a step each animation frame for `frames` frames; resolves to the frame rate
   *  between the first and the last frame. `lod` false: full surfaces while turning too. */
  function benchRotate(frames = 60, lod = true) {
    scene.lod = lod;
    return new Promise((resolve) => {
      let n = 0, t0 = 0, drawn = 0;
      function step(t) {
        if (n === 1) t0 = t;
        scene.rotate(3, 0);
        drawn = rowsView.render().drawn;
        if (++n <= frames) return requestAnimationFrame(step);
        scene.lod = true;
        resolve({ frames: frames - 1, seconds: (t - t0) / 1000, fps: ((frames - 1) * 1000) / (t - t0), cells_drawn: drawn });
      }
      requestAnimationFrame(step);
    });
  }

  return {
    manifest: app.manifest, state, scene, model, cohort, store, detail, rows: app.rows, marksLayer: app.marks, benchRotate,
    marks: () => Object.fromEntries(performance.getEntriesByType('mark').map((m) => [m.name, m.startTime])),
    bytes: () => store.loadedBytes,
    cells: () => all.map(describe),
    pixels: (i) => pixelsOf(all[i]),
    detailPixels: () => pixelsOf(detail.cell),
    camera: () => ({ ...scene.shared, zoom: scene.zoom }),
    rowView: (i) => all[i].row.view && { ...all[i].row.view },
    pick: (i, x, y) => { const f = scene.pick(all[i], x, y); return f < 0 ? -1 : model.element(painter.shellOf(all[i].row), f); },
    render: () => rowsView.render(),
    settled: async () => {  // every cell on screen drawn, and the rows near it read
      for (let k = 0; k < 400; ++k) {
        if (!rowsView.render().waiting && !store.pending) return true;
        await new Promise((r) => setTimeout(r, 20));
      }
      return false;
    },
  };
}
