/* The C interface between the message wrapper and a model plugin (a shared library built
 * from a stub written by `builtscene couple new-model`). Messages cross it LCM-encoded,
 * so a plugin needs only lcm-gen's generated types, not builtscene. Inputs are ordered as
 * the model's `subscribe` list, each subscription contributing `history` messages,
 * newest first; outputs are emitted by index in the order of the `publish` list. */
#ifndef BUILTSCENE_MODEL_ABI_H
#define BUILTSCENE_MODEL_ABI_H
#include <stddef.h>
#include <stdint.h>

#define BUILTSCENE_MODEL_ABI_VERSION 1

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const unsigned char* data;
  size_t size;
} bs_buffer;

typedef void (*bs_emit_fn)(void* context, size_t output_index, const unsigned char* data, size_t size);

/* Every plugin exports these four functions. Errors: return NULL / non-zero and write a
 * one-line message into `error`. */
int builtscene_model_abi_version(void);
void* builtscene_model_create(const char* parameters_json, char* error, size_t error_size);
int builtscene_model_step(void* model, int64_t step, double t, const bs_buffer* inputs, size_t n_inputs,
                          bs_emit_fn emit, void* context, char* error, size_t error_size);
void builtscene_model_destroy(void* model);

/* Optional checkpoint hooks (a plugin may lack them; the wrapper then resumes a restarted
 * model by replaying its inputs from step 0). can_checkpoint says whether the model
 * defines its save and load functions; save emits the state's bytes as output 0; load
 * restores a state from such bytes. */
int builtscene_model_can_checkpoint(void);
int builtscene_model_save(void* model, bs_emit_fn emit, void* context, char* error, size_t error_size);
int builtscene_model_load(void* model, const unsigned char* data, size_t size, char* error, size_t error_size);

#ifdef __cplusplus
}
#endif
#endif
