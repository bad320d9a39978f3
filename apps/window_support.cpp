#include "window_support.hpp"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <iostream>
#include <mutex>

namespace window_support {

namespace {

std::mutex error_mutex;
std::string error_text;
std::atomic<bool> stop{false};

extern "C" void on_glfw_error(int, const char* text) {
  std::lock_guard lock(error_mutex);
  error_text = text ? text : "unknown error";
}

extern "C" void on_stop_signal(int) {
  stop.store(true);
}

}  // namespace

void catch_glfw_errors() {
  glfwSetErrorCallback(on_glfw_error);
}

std::string last_glfw_error() {
  std::lock_guard lock(error_mutex);
  return error_text;
}

void watch_stop_signals(bool on) {
  std::signal(SIGINT, on ? on_stop_signal : SIG_DFL);
  std::signal(SIGTERM, on ? on_stop_signal : SIG_DFL);
}

bool stop_requested() {
  return stop.load();
}

GLFWwindow* open_window(const char* program, const char* title, int width, int height, bool vsync,
                        unsigned& texture, bool nearest) {
  catch_glfw_errors();
  if (!glfwInit()) {
    std::cerr << program << ": no display: cannot open a window (" << last_glfw_error()
              << "); set DISPLAY, or run under Xvfb for scripted use\n";
    return nullptr;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  GLFWwindow* window = glfwCreateWindow(width, height, title, nullptr, nullptr);
  if (!window) {
    std::cerr << program << ": cannot create an OpenGL 3.0 window: " << last_glfw_error() << "\n";
    glfwTerminate();
    return nullptr;
  }
  glfwMakeContextCurrent(window);
  // Shortcuts are polled once a frame: sticky keys keep a tap that is over before the poll.
  glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
  glfwSwapInterval(vsync ? 1 : 0);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 130");
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, nearest ? GL_NEAREST : GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return window;
}

void close_window(GLFWwindow* window, unsigned texture) {
  glDeleteTextures(1, &texture);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
}

int scripted_end(const char* program, bool want_shot, bool have_shot, int frames,
                 std::size_t frames_done) {
  const char* why = stop_requested() ? "interrupted" : "the window was closed";
  if (want_shot && !have_shot) {
    std::cerr << program << ": " << why << " before the final frame; nothing written\n";
    return 1;
  }
  if (frames > 0 && frames_done < std::size_t(frames)) {
    std::cerr << program << ": " << why << " after " << frames_done << " of " << frames
              << " frames; nothing written\n";
    return 1;
  }
  return 0;
}

std::vector<unsigned char> read_window(GLFWwindow* window, int& w, int& h) {
  glfwGetFramebufferSize(window, &w, &h);
  std::vector<unsigned char> rgb(std::size_t(w) * h * 3), flipped(rgb.size());
  glFinish();
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  const std::size_t row = std::size_t(w) * 3;
  for (int y = 0; y < h; ++y)  // OpenGL's rows start at the bottom
    std::copy_n(&rgb[std::size_t(h - 1 - y) * row], row, &flipped[std::size_t(y) * row]);
  return flipped;
}

}  // namespace window_support
