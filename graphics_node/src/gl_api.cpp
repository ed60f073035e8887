#include "gl_api.hpp"

#include <cstdio>
#include <stdexcept>
#include <string>

namespace handshare::render::detail {

namespace {

template <typename Fn>
void Resolve(GlApi::Loader loader, const char* name, Fn& fn) {
  const GlApi::Proc address = loader(name);
  if (address == nullptr) {
    throw std::runtime_error(std::string("OpenGL: the context does not provide ") + name);
  }
  fn = reinterpret_cast<Fn>(address);
}

// An optional entry point: null when the context lacks it.
template <typename Fn>
void ResolveOptional(GlApi::Loader loader, const char* name, Fn& fn) {
  fn = reinterpret_cast<Fn>(loader(name));
}

}  // namespace

void GlApi::Load(Loader loader) {
  Resolve(loader, "glBegin", Begin);
  Resolve(loader, "glBindTexture", BindTexture);
  Resolve(loader, "glBlendFunc", BlendFunc);
  Resolve(loader, "glClear", Clear);
  Resolve(loader, "glClearColor", ClearColor);
  Resolve(loader, "glColor3f", Color3f);
  Resolve(loader, "glColor4f", Color4f);
  Resolve(loader, "glColorMask", ColorMask);
  Resolve(loader, "glColorMaterial", ColorMaterial);
  Resolve(loader, "glDepthFunc", DepthFunc);
  Resolve(loader, "glDeleteTextures", DeleteTextures);
  Resolve(loader, "glDisableClientState", DisableClientState);
  Resolve(loader, "glDrawArrays", DrawArrays);
  Resolve(loader, "glDrawElements", DrawElements);
  Resolve(loader, "glEnableClientState", EnableClientState);
  Resolve(loader, "glDepthMask", DepthMask);
  Resolve(loader, "glDisable", Disable);
  Resolve(loader, "glDrawPixels", DrawPixels);
  Resolve(loader, "glEnable", Enable);
  Resolve(loader, "glEnd", End);
  Resolve(loader, "glFinish", Finish);
  Resolve(loader, "glGenTextures", GenTextures);
  Resolve(loader, "glGetError", GetError);
  Resolve(loader, "glLightModelfv", LightModelfv);
  Resolve(loader, "glLightModeli", LightModeli);
  Resolve(loader, "glLightfv", Lightfv);
  Resolve(loader, "glLineWidth", LineWidth);
  Resolve(loader, "glLoadIdentity", LoadIdentity);
  Resolve(loader, "glLoadMatrixd", LoadMatrixd);
  Resolve(loader, "glMaterialf", Materialf);
  Resolve(loader, "glMaterialfv", Materialfv);
  Resolve(loader, "glMatrixMode", MatrixMode);
  Resolve(loader, "glMultMatrixd", MultMatrixd);
  Resolve(loader, "glNormal3d", Normal3d);
  Resolve(loader, "glNormalPointer", NormalPointer);
  Resolve(loader, "glPixelStorei", PixelStorei);
  Resolve(loader, "glPopMatrix", PopMatrix);
  Resolve(loader, "glPushMatrix", PushMatrix);
  Resolve(loader, "glRasterPos2d", RasterPos2d);
  Resolve(loader, "glReadBuffer", ReadBuffer);
  Resolve(loader, "glReadPixels", ReadPixels);
  Resolve(loader, "glScissor", Scissor);
  Resolve(loader, "glShadeModel", ShadeModel);
  Resolve(loader, "glTexCoord2d", TexCoord2d);
  Resolve(loader, "glTexEnvi", TexEnvi);
  Resolve(loader, "glTexImage2D", TexImage2D);
  Resolve(loader, "glTexParameteri", TexParameteri);
  Resolve(loader, "glVertex2d", Vertex2d);
  Resolve(loader, "glVertex3d", Vertex3d);
  Resolve(loader, "glVertexPointer", VertexPointer);
  Resolve(loader, "glViewport", Viewport);
  Resolve(loader, "glFlush", Flush);
  ResolveOptional(loader, "glFenceSync", FenceSync);
  ResolveOptional(loader, "glClientWaitSync", ClientWaitSync);
  ResolveOptional(loader, "glDeleteSync", DeleteSync);
  if (FenceSync == nullptr || ClientWaitSync == nullptr || DeleteSync == nullptr) {
    FenceSync = nullptr;  // all three or none
    ClientWaitSync = nullptr;
    DeleteSync = nullptr;
  }
}

void GlApi::CheckError(const char* what) const {
  const GLenum error = GetError();
  if (error != GL_NO_ERROR) {
    throw std::runtime_error(std::string("OpenGL error 0x") + [error] {
      char hex[16];
      std::snprintf(hex, sizeof hex, "%04x", static_cast<unsigned>(error));
      return std::string(hex);
    }() + " during " + what);
  }
}

}  // namespace handshare::render::detail
