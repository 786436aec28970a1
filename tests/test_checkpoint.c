#include "tap.h"
#include "soilsim.h"
int main(void)
{
  ssModel *m = ss_model_new();
  ok(m != NULL, "model builds (checkpoint tests are being written)");
  ss_model_free(m);
  return done_testing();
}
