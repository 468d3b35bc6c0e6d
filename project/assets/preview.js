// The preview page of `rfd make`: a light-direction control and, for the light it sets, the
// field relit in software, the predicted display and their difference. The pictures are
// blended from the precomputed directions of data.js (window.RFD_PREVIEW) with rfd's own
// interpolation weights (relight/interpolation.hpp): inside a triangle of the directions'
// triangulation, vertex j weighs d . plane_j over the sum of the three. Blending is done on
// linear values (the atlases are sRGB). Plain script, no modules: it runs from file://.
(function () {
  "use strict";
  const data = window.RFD_PREVIEW;
  const page = (window.rfdPreview = { ready: false, light: { theta: 0, phi: 0 } });
  if (!data) return;

  const DEG = Math.PI / 180;
  const tileW = data.tile[0], tileH = data.tile[1], count = data.directions.length;
  const toLinear = new Float32Array(256);
  for (let i = 0; i < 256; ++i) {
    const c = i / 255;
    toLinear[i] = c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4);
  }
  const toCode = (v) => {
    const c = Math.min(1, Math.max(0, v));
    const s = c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055;
    return Math.round(255 * s);
  };

  // Every tile of an atlas as linear RGB floats.
  function decode(uri) {
    return new Promise((resolve, reject) => {
      const image = new Image();
      image.onload = () => {
        const canvas = document.createElement("canvas");
        canvas.width = image.width;
        canvas.height = image.height;
        const context = canvas.getContext("2d");
        context.drawImage(image, 0, 0);
        const pixels = context.getImageData(0, 0, image.width, image.height).data;
        const tiles = [];
        for (let k = 0; k < count; ++k) {
          const x0 = (k % data.columns) * tileW, y0 = Math.floor(k / data.columns) * tileH;
          const tile = new Float32Array(tileW * tileH * 3);
          for (let y = 0; y < tileH; ++y)
            for (let x = 0; x < tileW; ++x) {
              const i = ((y0 + y) * image.width + x0 + x) * 4, o = (y * tileW + x) * 3;
              tile[o] = toLinear[pixels[i]];
              tile[o + 1] = toLinear[pixels[i + 1]];
              tile[o + 2] = toLinear[pixels[i + 2]];
            }
          tiles.push(tile);
        }
        resolve(tiles);
      };
      image.onerror = () => reject(new Error("cannot decode a preview atlas"));
      image.src = uri;
    });
  }

  const direction = (theta, phi) => [
    Math.sin(theta * DEG) * Math.cos(phi * DEG),
    Math.sin(theta * DEG) * Math.sin(phi * DEG),
    Math.cos(theta * DEG),
  ];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

  // rfd's weights at unit d: [[index, weight], ...], or null outside the triangulation.
  function weights(d) {
    for (let t = 0; t < data.triangles.length; ++t) {
      const planes = data.edge_planes[t];
      const w = [dot(d, planes[0]), dot(d, planes[1]), dot(d, planes[2])];
      if (w[0] < -1e-14 || w[1] < -1e-14 || w[2] < -1e-14) continue;
      for (let j = 0; j < 3; ++j) w[j] = Math.max(0, w[j]);
      let sum = w[0] + w[1] + w[2];
      if (!(sum > 0)) continue;
      for (let j = 0; j < 3; ++j) if (w[j] < 1e-12 * sum) w[j] = 0;
      sum = w[0] + w[1] + w[2];
      return [0, 1, 2].map((j) => [data.triangles[t][j], w[j] / sum]);
    }
    return null;
  }

  // The light, kept inside the precomputed cone: toward the axis until the triangulation
  // holds it (its rim arcs cut slightly inside the cone).
  function setLight(theta, phi) {
    theta = Math.min(Math.max(theta, 0), data.max_angle_deg);
    phi = ((phi % 360) + 360) % 360;
    let w = weights(direction(theta, phi));
    while (!w && theta > 0) {
      theta = Math.max(0, theta - 0.05);
      w = weights(direction(theta, phi));
    }
    page.light = { theta: theta, phi: phi };
    page.weights = w;
    draw();
  }
  page.setLight = setLight;

  // With an optimised pattern, the direct encoding's pictures too, and a switch between them.
  let predicted = null, relit = null, direct = null;
  page.pattern = "optimised";
  const canvases = {
    relit: document.getElementById("relit"),
    predicted: document.getElementById("predicted"),
    difference: document.getElementById("difference"),
  };
  for (const name in canvases) {
    canvases[name].width = tileW;
    canvases[name].height = tileH;
  }

  function blend(tiles) {
    const out = new Float32Array(tileW * tileH * 3);
    for (const [index, weight] of page.weights) {
      if (weight === 0) continue;
      const tile = tiles[index];
      for (let i = 0; i < out.length; ++i) out[i] += weight * tile[i];
    }
    return out;
  }

  function show(canvas, values, gain) {
    const context = canvas.getContext("2d");
    const image = context.createImageData(tileW, tileH);
    for (let p = 0; p < tileW * tileH; ++p) {
      for (let c = 0; c < 3; ++c) image.data[p * 4 + c] = toCode(gain * values[p * 3 + c]);
      image.data[p * 4 + 3] = 255;
    }
    context.putImageData(image, 0, 0);
  }

  const disc = document.getElementById("light-disc");
  const readout = document.getElementById("light-readout");

  function discPoint(theta, phi, radius) {
    const r = (theta / data.max_angle_deg) * radius;
    return [disc.width / 2 + r * Math.cos(phi * DEG), disc.height / 2 - r * Math.sin(phi * DEG)];
  }

  function drawDisc() {
    const context = disc.getContext("2d");
    const radius = disc.width / 2 - 6;
    context.clearRect(0, 0, disc.width, disc.height);
    context.fillStyle = "#222";
    context.beginPath();
    context.arc(disc.width / 2, disc.height / 2, radius, 0, 2 * Math.PI);
    context.fill();
    const outline = (key, colour, dash) => {
      context.strokeStyle = colour;
      context.setLineDash(dash);
      context.beginPath();
      data.rims.forEach((rim, k) => {
        const angle = Math.min(rim[key] === null ? data.max_angle_deg : rim[key], data.max_angle_deg);
        const [x, y] = discPoint(angle, rim.phi_deg, radius);
        if (k === 0) context.moveTo(x, y);
        else context.lineTo(x, y);
      });
      context.closePath();
      context.stroke();
      context.setLineDash([]);
    };
    outline("wrap_over_deg", "#e55", [4, 3]);
    outline("crosstalk_deg", "#eb3", []);
    const [x, y] = discPoint(page.light.theta, page.light.phi, radius);
    context.fillStyle = "#fff";
    context.beginPath();
    context.arc(x, y, 5, 0, 2 * Math.PI);
    context.fill();
  }

  function draw() {
    drawDisc();
    readout.textContent =
      "light " + page.light.theta.toFixed(1) + "\u00b0 from the display's axis, azimuth " +
      page.light.phi.toFixed(1) + "\u00b0";
    if (!predicted || !page.weights) return;
    const p = blend(page.pattern === "direct" && direct ? direct : predicted), r = blend(relit);
    const difference = new Float32Array(p.length);
    for (let i = 0; i < p.length; ++i) difference[i] = Math.abs(p[i] - r[i]);
    show(canvases.predicted, p, 1);
    show(canvases.relit, r, 1);
    show(canvases.difference, difference, 4);
  }

  // The control: drag on the disc (as OpenLIME's light sphere), or the arrow keys.
  function fromPointer(event) {
    const box = disc.getBoundingClientRect();
    const radius = disc.width / 2 - 6;
    const x = ((event.clientX - box.left) * disc.width) / box.width - disc.width / 2;
    const y = disc.height / 2 - ((event.clientY - box.top) * disc.height) / box.height;
    const r = Math.min(Math.hypot(x, y) / radius, 1);
    setLight(r * data.max_angle_deg, Math.atan2(y, x) / DEG);
  }
  let dragging = false;
  disc.addEventListener("pointerdown", (event) => {
    dragging = true;
    if (disc.setPointerCapture && event.pointerId !== undefined) {
      try { disc.setPointerCapture(event.pointerId); } catch (e) { /* synthetic events have no capture */ }
    }
    fromPointer(event);
  });
  disc.addEventListener("pointermove", (event) => { if (dragging) fromPointer(event); });
  disc.addEventListener("pointerup", () => { dragging = false; });
  disc.addEventListener("keydown", (event) => {
    const d = direction(page.light.theta, page.light.phi);
    const step = 0.5 * DEG;
    const moves = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, step], ArrowDown: [0, -step] };
    const move = moves[event.key];
    if (!move) return;
    event.preventDefault();
    const x = Math.asin(Math.max(-1, Math.min(1, d[0]))) + move[0], y = Math.asin(Math.max(-1, Math.min(1, d[1]))) + move[1];
    setLight(Math.hypot(x, y) / DEG, Math.atan2(y, x) / DEG);
  });

  if (data.predicted_direct) {
    const figure = canvases.predicted.parentElement;
    const choice = document.createElement("div");
    choice.id = "pattern-choice";
    for (const [value, label] of [["optimised", "optimised pattern"], ["direct", "direct encoding"]]) {
      const option = document.createElement("label");
      const input = document.createElement("input");
      input.type = "radio";
      input.name = "pattern";
      input.value = value;
      input.checked = value === page.pattern;
      input.addEventListener("change", () => setPattern(value));
      option.append(input, " " + label + " ");
      choice.append(option);
    }
    figure.append(choice);
  }
  function setPattern(value) {
    page.pattern = value;
    for (const input of document.querySelectorAll("#pattern-choice input")) input.checked = input.value === value;
    draw();
  }
  page.setPattern = setPattern;

  setLight(0, 0);
  Promise.all([decode(data.predicted), decode(data.relit), data.predicted_direct ? decode(data.predicted_direct) : null])
    .then(([p, r, d]) => {
      predicted = p;
      relit = r;
      direct = d;
      draw();
      page.ready = true;
    });

  // The holder in 3D, when three.js was vendored beside this page.
  const webgl = (() => {
    try {
      return !!document.createElement("canvas").getContext("webgl");
    } catch (e) {
      return false;
    }
  })();
  const host = document.getElementById("holder-view");
  if (host && !(window.THREE && window.RFD_HOLDER && webgl))
    host.textContent = window.RFD_HOLDER
      ? (webgl ? "three.js was not installed when this page was made (Debian: libjs-three): open the STLs instead."
               : "This browser has no WebGL: open the STLs instead.")
      : "No holder was made.";
  else if (host && THREE.STLLoader && THREE.OrbitControls) {
    const renderer = new THREE.WebGLRenderer({ antialias: true });
    renderer.setSize(host.clientWidth, 360);
    host.appendChild(renderer.domElement);
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0xf4f4f4);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 1.0));
    const sun = new THREE.DirectionalLight(0xffffff, 0.6);
    sun.position.set(1, 2, 3);
    scene.add(sun);
    const camera = new THREE.PerspectiveCamera(35, host.clientWidth / 360, 1, 5000);
    const loader = new THREE.STLLoader();
    const box = new THREE.Box3();
    const colours = [0x5b8dd6, 0xd68b5b, 0x6bbf6b];
    window.RFD_HOLDER.forEach((part, k) => {
      const bytes = Uint8Array.from(atob(part.stl), (c) => c.charCodeAt(0));
      const geometry = loader.parse(bytes.buffer);
      const mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: colours[k % 3] }));
      geometry.computeBoundingBox();
      const size = geometry.boundingBox.getSize(new THREE.Vector3());
      mesh.position.x = k * (size.x + 10);  // parts side by side
      scene.add(mesh);
      box.expandByObject(mesh);
    });
    const centre = box.getCenter(new THREE.Vector3()), extent = box.getSize(new THREE.Vector3()).length();
    camera.position.set(centre.x + extent * 0.6, centre.y - extent * 1.2, centre.z + extent * 0.9);
    camera.up.set(0, 0, 1);
    const controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.target.copy(centre);
    controls.update();
    const render = () => renderer.render(scene, camera);
    controls.addEventListener("change", render);
    render();
  }
})();
