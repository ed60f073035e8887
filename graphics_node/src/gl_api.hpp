#pragma once
// OpenGL entry points used by the scene drawer, loaded through the context's own
// GetProcAddress. Why not call gl* directly: the library links both libOSMesa (offscreen) and
// GLVND's libGL (GLFW windows), which export the same gl* symbols; whichever the dynamic linker
// binds first would silently swallow the other's calls (verified: with libGL first, glClear on
// an OSMesa context draws nothing). Loading per context makes each path call its own driver.

#include <GL/gl.h>
#include <GL/glext.h>

namespace handshare::render::detail {

struct GlApi {
  using Proc = void (*)();
  using Loader = Proc (*)(const char* name);

  // Filled by Load(); every pointer is non-null after a successful load.
  decltype(&::glBegin) Begin = nullptr;
  decltype(&::glBindTexture) BindTexture = nullptr;
  decltype(&::glBlendFunc) BlendFunc = nullptr;
  decltype(&::glClear) Clear = nullptr;
  decltype(&::glClearColor) ClearColor = nullptr;
  decltype(&::glColor3f) Color3f = nullptr;
  decltype(&::glColor4f) Color4f = nullptr;
  decltype(&::glColorMask) ColorMask = nullptr;
  decltype(&::glColorMaterial) ColorMaterial = nullptr;
  decltype(&::glDepthFunc) DepthFunc = nullptr;
  decltype(&::glDeleteTextures) DeleteTextures = nullptr;
  decltype(&::glDisableClientState) DisableClientState = nullptr;
  decltype(&::glDrawArrays) DrawArrays = nullptr;
  decltype(&::glDrawElements) DrawElements = nullptr;
  decltype(&::glEnableClientState) EnableClientState = nullptr;
  decltype(&::glDepthMask) DepthMask = nullptr;
  decltype(&::glDisable) Disable = nullptr;
  decltype(&::glDrawPixels) DrawPixels = nullptr;
  decltype(&::glEnable) Enable = nullptr;
  decltype(&::glEnd) End = nullptr;
  decltype(&::glFinish) Finish = nullptr;
  decltype(&::glGenTextures) GenTextures = nullptr;
  decltype(&::glGetError) GetError = nullptr;
  decltype(&::glLightModelfv) LightModelfv = nullptr;
  decltype(&::glLightModeli) LightModeli = nullptr;
  decltype(&::glLightfv) Lightfv = nullptr;
  decltype(&::glLineWidth) LineWidth = nullptr;
  decltype(&::glLoadIdentity) LoadIdentity = nullptr;
  decltype(&::glLoadMatrixd) LoadMatrixd = nullptr;
  decltype(&::glMaterialf) Materialf = nullptr;
  decltype(&::glMaterialfv) Materialfv = nullptr;
  decltype(&::glMatrixMode) MatrixMode = nullptr;
  decltype(&::glMultMatrixd) MultMatrixd = nullptr;
  decltype(&::glNormal3d) Normal3d = nullptr;
  decltype(&::glNormalPointer) NormalPointer = nullptr;
  decltype(&::glPixelStorei) PixelStorei = nullptr;
  decltype(&::glPopMatrix) PopMatrix = nullptr;
  decltype(&::glPushMatrix) PushMatrix = nullptr;
  decltype(&::glRasterPos2d) RasterPos2d = nullptr;
  decltype(&::glReadBuffer) ReadBuffer = nullptr;
  decltype(&::glReadPixels) ReadPixels = nullptr;
  decltype(&::glScissor) Scissor = nullptr;
  decltype(&::glShadeModel) ShadeModel = nullptr;
  decltype(&::glTexCoord2d) TexCoord2d = nullptr;
  decltype(&::glTexEnvi) TexEnvi = nullptr;
  decltype(&::glTexImage2D) TexImage2D = nullptr;
  decltype(&::glTexParameteri) TexParameteri = nullptr;
  decltype(&::glVertex2d) Vertex2d = nullptr;
  decltype(&::glVertex3d) Vertex3d = nullptr;
  decltype(&::glVertexPointer) VertexPointer = nullptr;
  decltype(&::glViewport) Viewport = nullptr;
  decltype(&::glFlush) Flush = nullptr;

  // Optional (OpenGL 3.2 / ARB_sync; null when the context lacks them): a fence after a frame's
  // commands, so that the caller can do other work while the driver draws.
  PFNGLFENCESYNCPROC FenceSync = nullptr;
  PFNGLCLIENTWAITSYNCPROC ClientWaitSync = nullptr;
  PFNGLDELETESYNCPROC DeleteSync = nullptr;

  /// Resolves every entry point with `loader` (the current context's GetProcAddress).
  /// Throws std::runtime_error naming the first missing function (of the required ones).
  void Load(Loader loader);

  /// Throws std::runtime_error with `what` if glGetError reports an error.
  void CheckError(const char* what) const;
};

}  // namespace handshare::render::detail
