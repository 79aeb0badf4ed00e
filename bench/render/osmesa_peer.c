// SPDX-License-Identifier: GPL-3.0-or-later
// The peer for bench/render: the same torus drawn offscreen by Mesa (OSMesa, gallium llvmpipe),
// fixed-function lighting, z-buffer, read back. Built by run_render_bench.sh when libosmesa6-dev
// is installed:  cc -O2 osmesa_peer.c -lOSMesa -lm
//   osmesa_peer mesh|points N WIDTH HEIGHT SCALE   (SCALE: supersampling by a larger buffer)
// Prints one JSON line: context creation, draw (upload, draw, glFinish) and read-back seconds.
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char** argv) {
  if (argc < 6) return 1;
  const int mesh = strcmp(argv[1], "mesh") == 0;
  const long n = atol(argv[2]);
  const int w = atoi(argv[3]) * atoi(argv[5]), h = atoi(argv[4]) * atoi(argv[5]);
  int nu = (int)sqrt(n / 2.0 * 3.0), nv = (int)(n / 2.0 / nu);
  long nvert = mesh ? (long)nu * nv : n;
  float* v = malloc(sizeof(float) * 3 * nvert);
  float* nn = malloc(sizeof(float) * 3 * nvert);
  srand(7);
  for (long k = 0; k < nvert; ++k) {
    double u = mesh ? 2 * M_PI * (k / nv) / nu : 2 * M_PI * rand() / RAND_MAX;
    double t = mesh ? 2 * M_PI * (k % nv) / nv : 2 * M_PI * rand() / RAND_MAX;
    v[3 * k] = (float)((3 + cos(t)) * cos(u));
    v[3 * k + 1] = (float)((3 + cos(t)) * sin(u));
    v[3 * k + 2] = (float)sin(t);
    nn[3 * k] = (float)(cos(t) * cos(u));
    nn[3 * k + 1] = (float)(cos(t) * sin(u));
    nn[3 * k + 2] = (float)sin(t);
  }
  long ntri = mesh ? 2L * nu * nv : 0;
  unsigned* idx = malloc(sizeof(unsigned) * 3 * (ntri ? ntri : 1));
  for (int i = 0, f = 0; mesh && i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      unsigned a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
      unsigned q[6] = {a, b, c, a, c, d};
      memcpy(idx + 6L * f++, q, sizeof q);
    }
  double t0 = now();
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  unsigned char* buffer = malloc((size_t)w * h * 4);
  if (!ctx || !OSMesaMakeCurrent(ctx, buffer, GL_UNSIGNED_BYTE, w, h)) {
    printf("{\"peer\": \"osmesa\", \"error\": \"no context\"}\n");
    return 1;
  }
  double t1 = now();
  glViewport(0, 0, w, h);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glOrtho(-4.5 * w / h, 4.5 * w / h, -4.5, 4.5, -10, 10);
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glRotatef(-55, 1, 0, 0);
  glRotatef(-45, 0, 0, 1);
  glEnable(GL_DEPTH_TEST);
  glClearColor(1, 1, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT0);
  glEnable(GL_NORMALIZE);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glVertexPointer(3, GL_FLOAT, 0, v);
  glNormalPointer(GL_FLOAT, 0, nn);
  if (mesh) {
    glDrawElements(GL_TRIANGLES, (GLsizei)(3 * ntri), GL_UNSIGNED_INT, idx);
  } else {
    glPointSize(2.0f * atoi(argv[5]));
    glDrawArrays(GL_POINTS, 0, (GLsizei)nvert);
  }
  glFinish();
  double t2 = now();
  unsigned char* pixels = malloc((size_t)w * h * 4);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
  double t3 = now();
  long lit = 0;
  for (long k = 0; k < (long)w * h; ++k) lit += pixels[4 * k] != 255 || pixels[4 * k + 1] != 255;
  printf("{\"peer\": \"osmesa %s\", \"kind\": \"%s\", \"points\": %ld, \"triangles\": %ld, \"buffer\": \"%dx%d\", \"context_s\": %.4f, "
         "\"draw_s\": %.4f, \"readback_s\": %.4f, \"total_s\": %.4f, \"covered_pixels\": %ld}\n",
         (const char*)glGetString(GL_RENDERER), argv[1], nvert, ntri, w, h, t1 - t0, t2 - t1, t3 - t2, t3 - t0, lit);
  OSMesaDestroyContext(ctx);
  return 0;
}
