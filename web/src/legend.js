// The legend above the tables: what the numbers are (units of the normalised values, the z-scores
// of patients and of normals, which direction was searched for foci and how), written from the
// options vpm compare used (the manifest's features).
import { esc } from './table.js';
import { fmt, thousands } from './plot.js';

function direction(sign) {
  if (sign < 0) return { short: 'below the normals only', long: 'decreases only (z below \u2212threshold; increases were not searched)' };
  if (sign > 0) return { short: 'above the normals only', long: 'increases only (z above +threshold; decreases were not searched)' };
  return { short: 'above and below the normals', long: 'increases and decreases' };
}

function units(f) {
  return f.normalisation === 'proportional'
    ? `${esc(f.name)} divided by the subject's own global mean (proportional scaling, as PET analyses do): 1.0 is the subject's mean, 0.8 is 20 % below it`
    : `${esc(f.name)} as sampled (no scaling)`;
}

function test(f) {
  return f.test === 'crawford-howell'
    ? "Crawford and Howell's single-case t against the normals, given as the z of the same tail probability"
    : '(value \u2212 normals\u2019 mean) / normals\u2019 standard deviation';
}

function threshold(f) {
  const cut = f.fdr_q > 0 ? `a false discovery rate of ${fmt(f.fdr_q)}` : `|z| \u2265 ${fmt(f.threshold)}`;
  return `${cut} in clusters of at least ${f.min_cluster} adjacent elements` +
    (f.extend > 0 ? `, grown into neighbours with |z| \u2265 ${fmt(f.extend)}` : '') +
    (f.peak > 0 ? `; smaller clusters count when their peak |z| \u2265 ${fmt(f.peak)}` : '');
}

/** Fills the legend (a <details> element): one summary line, the rest on opening. */
export function buildLegend(el, manifest) {
  const fs = manifest.features;
  const n = manifest.subjects.filter((s) => s.group !== 'patient').length;
  const dirs = [...new Set(fs.map((f) => direction(f.sign).short))].join('; ');
  el.innerHTML = `<summary>Legend: values are ${fs.some((f) => f.normalisation === 'proportional') ? 'proportionally scaled (1 = the subject\u2019s mean)' : 'as sampled'}; ` +
    `z: patients against all ${n} normals, each normal against the other ${n - 1} (leave-one-out); foci searched ${dirs}.</summary>` +
    '<dl>' + fs.map((f) => {
      const d = direction(f.sign);
      const cov = (f.covariates || []).map(esc).join(', ');
      return `<dt>${esc(f.name)}</dt><dd><b>value</b>: ${units(f)}. <b>z</b>: ${test(f)}. ` +
        (cov ? `The reference models ${cov}: each patient is compared with the value its own ${cov} predict ` +
          `(a normal's leave-one-out z below uses the normals' mean ${cov}). ` : '') +
        (f.image_covariate ? `Each element's reference also models the subjects' own ${esc(f.image_covariate)} there: a ` +
          `patient is compared with the value its own ${esc(f.image_covariate)} predicts, so that what the structure ` +
          `explains (grey matter a little off its place) is not read as a focus (a normal's leave-one-out z ignores it). ` : '') +
        `A patient's z is against the reference of all ${f.reference_subjects} normals; a normal's z is ` +
        `leave-one-out, against the other ${f.reference_subjects - 1} normals, so that it is comparable with a patient's ` +
        `(a normal against a reference that holds it would look closer to the normals than it is). ` +
        `<b>Foci</b> (saturated colours; other elements beyond the threshold are faded): ${threshold(f)}, ` +
        `searched for ${d.long}` + (f.smoothing > 0 ? `, after averaging over ${f.smoothing} ring(s) of neighbouring elements` : '') + '.</dd>';
    }).join('') +
    `<dt>elements</dt><dd>${thousands(manifest.elements)} canonical volume elements of the unit ball (level ${manifest.definition.level}, ` +
    `${manifest.shells} shells of equal volume); every subject is mapped to the ball, so an element is the same ` +
    'anatomical place in every brain. The shell slider shows one shell (the outer one is the brain\u2019s surface).' +
    (manifest.compared ? ` The comparisons used ${thousands(manifest.compared.elements)} finer elements (level ` +
      `${manifest.compared.level}); each element here shows the mean of the finer ones inside it.` : '') + '</dd>' +
    '<dt>reference row</dt><dd>the normals\u2019 mean (value columns) and spread, their standard deviation (z columns), on their mean shape.</dd>' +
    '<dt>keys</dt><dd>Tab moves between cells and the foci table; arrow keys turn every brain; + and \u2212 (or Ctrl + wheel) zoom; ' +
    'Enter opens the detail of a cell; Escape closes it.</dd></dl>';
}
