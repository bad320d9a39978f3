// Storage of HRC's T and R: f32, or f16 (--storage f16, seed 004's choice) when the shader is
// compiled with PENUMBRA_F16. Values are loaded as float(x) and stored as stored_t(x), so the
// arithmetic stays f32 as on the CPU, and memory carries half the bytes.
#ifdef PENUMBRA_F16
#extension GL_EXT_shader_16bit_storage : require
#define stored_t float16_t
#else
#define stored_t float
#endif
