// Does a learned decoder (in the spirit of NeuralRTI: a per-pixel code from an encoder over
// the pixel's samples, a small decoder of code and light direction) predict held-out lights
// better than rfd's light models? Four folds (every fourth light held out), the same folds for
// every method, PSNR in 8-bit sRGB codes as relight eval reports it.
// Usage: rfd_neural_study FIELD [EPOCHS] [SAMPLE_PIXELS] [BATCH] [LEARNING_RATE] [FOLDS_RUN]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <torch/torch.h>

#include "core/image.hpp"
#include "relight/field.hpp"
#include "relight/light_model.hpp"

using namespace rfd;
using namespace rfd::relight;

namespace {

int code8(float linear) {
    return static_cast<int>(std::lround(255.0f * linear_to_srgb(std::clamp(linear, 0.0f, 1.0f))));
}

struct Net : torch::nn::Module {
    Net(int inputs, int code) {
        encoder = register_module("encoder", torch::nn::Sequential(
                                                 torch::nn::Linear(inputs, 150), torch::nn::ELU(),
                                                 torch::nn::Linear(150, 150), torch::nn::ELU(),
                                                 torch::nn::Linear(150, 150), torch::nn::ELU(),
                                                 torch::nn::Linear(150, code)));
        decoder = register_module("decoder", torch::nn::Sequential(
                                                 torch::nn::Linear(code + 2, 50), torch::nn::ELU(),
                                                 torch::nn::Linear(50, 50), torch::nn::ELU(),
                                                 torch::nn::Linear(50, 50), torch::nn::ELU(),
                                                 torch::nn::Linear(50, 3)));
    }
    torch::nn::Sequential encoder{nullptr}, decoder{nullptr};
};

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s FIELD [EPOCHS] [SAMPLE_PIXELS]\n", argv[0]);
        return 2;
    }
    const int epochs = argc > 2 ? std::stoi(argv[2]) : 40;
    const int sample_pixels = argc > 3 ? std::stoi(argv[3]) : 1 << 15;
    const long batch = argc > 4 ? std::stol(argv[4]) : 256;
    const double rate = argc > 5 ? std::stod(argv[5]) : 1e-3;
    const int folds_run = argc > 6 ? std::stoi(argv[6]) : 4;
    torch::manual_seed(1);
    torch::set_num_threads(2);
    const ReflectanceField field = read_field(argv[1]);
    const std::size_t n = field.size();
    const int width = field.width(), height = field.height(), pixels = width * height;
    const std::vector<Eigen::Vector3d>& dirs = field.directions;
    // Display values per pixel: [pixels, n, 3].
    torch::Tensor display = torch::empty({pixels, static_cast<long>(n), 3});
    auto d = display.accessor<float, 3>();
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < pixels; ++k)
                d[k][static_cast<long>(i)][c] =
                    linear_to_srgb(std::clamp(field.images[i].at(k % width, k / width, field.channels() == 1 ? 0 : c), 0.0f, 1.0f));

    const std::vector<std::string> names{"delaunay", "rbf", "bilinear", "hsh3"};
    std::vector<double> sum_psnr(names.size() + 1, 0.0);
    std::size_t held_total = 0;
    const auto psnr8 = [&](const std::vector<int>& a, const std::vector<int>& b) {
        double se = 0.0;
        for (std::size_t k = 0; k < a.size(); ++k) se += double(a[k] - b[k]) * double(a[k] - b[k]);
        return psnr_from_mse(se / static_cast<double>(a.size()), 255.0);
    };
    for (int fold = 0; fold < folds_run; ++fold) {
        std::vector<std::size_t> train, held;
        for (std::size_t i = 0; i < n; ++i) (static_cast<int>(i % 4) == fold ? held : train).push_back(i);
        std::vector<Eigen::Vector3d> train_dirs;
        for (std::size_t i : train) train_dirs.push_back(dirs[i]);
        ReflectanceField sub;
        sub.directions = train_dirs;
        for (std::size_t i : train) sub.images.push_back(field.images[i]);
        const FieldGram gram = field_gram(sub);
        std::vector<std::vector<int>> truth(held.size());
        for (std::size_t h = 0; h < held.size(); ++h)
            for (int k = 0; k < pixels; ++k)
                for (int c = 0; c < 3; ++c)
                    truth[h].push_back(code8(field.images[held[h]].at(k % width, k / width, field.channels() == 1 ? 0 : c)));
        for (std::size_t m = 0; m < names.size(); ++m) {
            LightModel model = parse_light_model(names[m]);
            if (model.has_sigma()) model.sigma = best_sigma(gram, train_dirs, model);
            const LightWeights weights(model, train_dirs);
            for (std::size_t h = 0; h < held.size(); ++h) {
                const Eigen::VectorXd w = weights.at(dirs[held[h]]);
                std::vector<int> pred;
                for (int k = 0; k < pixels; ++k)
                    for (int c = 0; c < 3; ++c) {
                        double v = 0.0;
                        for (std::size_t t = 0; t < train.size(); ++t)
                            v += w[static_cast<Eigen::Index>(t)] *
                                 sub.images[t].at(k % width, k / width, field.channels() == 1 ? 0 : c);
                        pred.push_back(code8(static_cast<float>(v)));
                    }
                sum_psnr[m] += psnr8(pred, truth[h]);
            }
        }
        // The learned decoder, trained on a sample of pixels under the training lights.
        const auto t0 = std::chrono::steady_clock::now();
        const long m_train = static_cast<long>(train.size());
        torch::Tensor index = torch::tensor(std::vector<long>(train.begin(), train.end()), torch::kLong);
        torch::Tensor inputs = display.index_select(1, index);  // [pixels, m, 3]
        torch::Tensor train_lights = torch::empty({m_train, 2});
        for (long t = 0; t < m_train; ++t) {
            train_lights[t][0] = dirs[train[static_cast<std::size_t>(t)]].x();
            train_lights[t][1] = dirs[train[static_cast<std::size_t>(t)]].y();
        }
        Net net(3 * static_cast<int>(m_train), 9);
        torch::optim::Adam optimizer(net.parameters(), torch::optim::AdamOptions(rate));
        std::mt19937 random(7);
        std::vector<long> order(static_cast<std::size_t>(pixels));
        for (int k = 0; k < pixels; ++k) order[static_cast<std::size_t>(k)] = k;
        std::shuffle(order.begin(), order.end(), random);
        order.resize(static_cast<std::size_t>(std::min(sample_pixels, pixels)));
        torch::Tensor sample = inputs.index_select(0, torch::tensor(order, torch::kLong));  // [P, m, 3]
        const long count = sample.size(0);
        double last_loss = 0.0;
        for (int epoch = 0; epoch < epochs; ++epoch) {
            torch::Tensor perm = torch::randperm(count, torch::kLong);
            double total = 0.0;
            for (long b0 = 0; b0 < count; b0 += batch) {
                const long b1 = std::min(count, b0 + batch), bn = b1 - b0;
                torch::Tensor x = sample.index_select(0, perm.slice(0, b0, b1));  // [bn, m, 3]
                torch::Tensor code = net.encoder->forward(x.reshape({bn, 3 * m_train}));
                torch::Tensor dec_in = torch::cat({code.unsqueeze(1).expand({bn, m_train, 9}),
                                                   train_lights.unsqueeze(0).expand({bn, m_train, 2})},
                                                  2)
                                           .reshape({bn * m_train, 11});
                torch::Tensor out = net.decoder->forward(dec_in).reshape({bn, m_train, 3});
                torch::Tensor loss = torch::mse_loss(out, x);
                optimizer.zero_grad();
                loss.backward();
                optimizer.step();
                total += loss.item<double>() * static_cast<double>(bn);
            }
            last_loss = total / static_cast<double>(count);
            if (epoch == epochs / 2)
                for (auto& group : optimizer.param_groups())
                    static_cast<torch::optim::AdamOptions&>(group.options()).lr(rate * 0.3);
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        torch::NoGradGuard no_grad;
        torch::Tensor codes = net.encoder->forward(inputs.reshape({pixels, 3 * m_train}));  // [pixels, 9]
        for (std::size_t h = 0; h < held.size(); ++h) {
            torch::Tensor light = torch::tensor({static_cast<float>(dirs[held[h]].x()), static_cast<float>(dirs[held[h]].y())});
            torch::Tensor out =
                net.decoder->forward(torch::cat({codes, light.unsqueeze(0).expand({pixels, 2})}, 1));  // [pixels, 3]
            auto o = out.accessor<float, 2>();
            std::vector<int> pred;
            for (int k = 0; k < pixels; ++k)
                for (int c = 0; c < 3; ++c)
                    pred.push_back(static_cast<int>(std::lround(255.0 * std::clamp(o[k][c], 0.0f, 1.0f))));
            sum_psnr[names.size()] += psnr8(pred, truth[h]);
        }
        held_total += held.size();
        std::fprintf(stderr, "fold %d: %zu held out, decoder trained in %.0f s (train MSE %.3g, %.2f dB)\n", fold,
                     held.size(), seconds, last_loss, psnr_from_mse(last_loss, 1.0));
    }
    std::printf("%s: mean PSNR (8-bit sRGB) of the held-out lights, %d of 4 folds, %d epochs of %d pixels, batch %ld\n", argv[1], folds_run, epochs, sample_pixels, batch);
    for (std::size_t m = 0; m <= names.size(); ++m)
        std::printf("  %-9s %.2f dB\n", m < names.size() ? names[m].c_str() : "neural", sum_psnr[m] / static_cast<double>(held_total));
}
