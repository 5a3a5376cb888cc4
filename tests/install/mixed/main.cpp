// Frees blocks allocated by another Eigen library and by msdeform, in one program.
#include <cstdio>

#include <msdeform/core/scenes.h>

Eigen::VectorXd other_ones(int n);

int main() {
  double sum = 0;
  for (int i = 0; i < 1000; ++i) sum += other_ones(1000 + i).sum();  // freed here, by this program's Eigen
  const msd::Scene scene = msd::make_scene("lift");  // allocated by msdeform, freed here
  sum += scene.P.rows();
  std::printf("mixed: %.0f\n", sum);
  return sum > 0 ? 0 : 1;
}
