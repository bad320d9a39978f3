// What the painter's and the viewer's windows share: GLFW's error text, SIGINT and SIGTERM
// ending a session as closing the window does, and reading the window back for a screenshot.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

struct GLFWwindow;

namespace window_support {

// Sets GLFW's error callback; last_glfw_error() is the latest error's text (it may be reported on
// another thread, through glfwPostEmptyEvent).
void catch_glfw_errors();
std::string last_glfw_error();

// SIGINT and SIGTERM set stop_requested() instead of ending the program (on), or end it again
// (off).
void watch_stop_signals(bool on);
bool stop_requested();

// Opens a fixed-size OpenGL 3.0 window with Dear ImGui (no imgui.ini, sticky keys, vsync where
// `vsync`) and a texture for the picture (`texture`: linear minification, clamped, magnification
// `nearest`); null after printing "<program>: no display ..." or why the window cannot be made.
GLFWwindow* open_window(const char* program, const char* title, int width, int height, bool vsync,
                        unsigned& texture, bool nearest);
// Deletes the texture, shuts Dear ImGui and GLFW down.
void close_window(GLFWwindow* window, unsigned texture);

// A scripted run's end: 1 with a message where it stopped before its screenshot or its `frames`
// (the window was closed or a signal came), else 0.
int scripted_end(const char* program, bool want_shot, bool have_shot, int frames,
                 std::size_t frames_done);

// The window's back buffer as 8-bit RGB, row 0 at the top.
std::vector<unsigned char> read_window(GLFWwindow* window, int& width, int& height);

}  // namespace window_support
