// EXR reading and writing with OpenEXR: channels found by name, converted to float, the data
// window's origin wherever it lies; every OpenEXR exception becomes an rtd::Error naming the file.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfThreading.h>

#include <cstddef>
#include <exception>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "io/atomic_file.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace {

std::string quotedList(const std::vector<std::string>& names, const char* lastSeparator) {
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i) {
        if (i > 0) out += (i + 1 == names.size()) ? lastSeparator : ", ";
        out += "'" + names[i] + "'";
    }
    return out;
}

std::string channelNames(const Imf::ChannelList& channels) {
    std::string out;
    int count = 0;
    for (auto it = channels.begin(); it != channels.end(); ++it, ++count) {
        if (count == 24) return out + ", ...";  // keep messages readable for layered files
        if (count > 0) out += ", ";
        out += it.name();
    }
    return count == 0 ? std::string("no channels") : out;
}

}  // namespace

void setExrThreads(int count) {
    Imf::setGlobalThreadCount(count < 0 ? 0 : count);
}

Image readExr(const std::filesystem::path& file,
              const std::vector<std::vector<std::string>>& channelChoices) {
    if (channelChoices.empty()) {
        throw Error(ErrorCode::InvalidArgument, file.string() + ": no channels requested");
    }
    std::error_code ec;
    if (!std::filesystem::exists(file, ec) && !ec) {
        throw Error(ErrorCode::MissingFile, file.string() + ": no such file");
    }
    try {
        Imf::InputFile input(file.c_str(), Imf::globalThreadCount());
        const Imf::Header& header = input.header();
        const Imf::ChannelList& channels = header.channels();

        // Resolve every output channel to a file channel before reading anything.
        std::vector<std::string> chosen;
        for (const auto& choices : channelChoices) {
            const std::string* found = nullptr;
            for (const auto& name : choices) {
                if (channels.findChannel(name)) {
                    found = &name;
                    break;
                }
            }
            if (!found) {
                throw Error(ErrorCode::InvalidInput, file.string() + ": missing channel " +
                                                         quotedList(choices, " or ") +
                                                         " (has: " + channelNames(channels) + ")");
            }
            const Imf::Channel* channel = channels.findChannel(*found);
            if (channel->xSampling != 1 || channel->ySampling != 1) {
                throw Error(ErrorCode::InvalidInput, file.string() + ": channel '" + *found +
                                                         "' is subsampled, which is not supported");
            }
            chosen.push_back(*found);
        }

        const Imath::Box2i window = header.dataWindow();
        const int width = window.max.x - window.min.x + 1;
        const int height = window.max.y - window.min.y + 1;
        if (width <= 0 || height <= 0) {
            throw Error(ErrorCode::InvalidInput, file.string() + ": empty data window");
        }
        const int channelCount = static_cast<int>(chosen.size());
        Image image(width, height, channelCount);

        // A FrameBuffer holds one slice per name, so an output channel that repeats an earlier
        // one is copied after the read instead.
        const std::size_t xStride = sizeof(float) * channelCount;
        const std::size_t yStride = xStride * width;
        Imf::FrameBuffer frameBuffer;
        std::vector<int> copyOf(chosen.size(), -1);
        for (int c = 0; c < channelCount; ++c) {
            for (int earlier = 0; earlier < c; ++earlier) {
                if (chosen[earlier] == chosen[c]) {
                    copyOf[c] = earlier;
                    break;
                }
            }
            if (copyOf[c] >= 0) continue;
            frameBuffer.insert(chosen[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c,
                                                           window, xStride, yStride));
        }
        input.setFrameBuffer(frameBuffer);
        input.readPixels(window.min.y, window.max.y);

        for (int c = 0; c < channelCount; ++c) {
            if (copyOf[c] < 0) continue;
            for (std::size_t i = 0; i < image.pixelCount(); ++i) {
                image.pixels[i * channelCount + c] = image.pixels[i * channelCount + copyOf[c]];
            }
        }
        return image;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": " + e.what());
    }
}

void writeExr(const std::filesystem::path& file, const Image& image) {
    // 3 channels are written as R,G,B; 1 channel as Y (the layout's depth and ID files).
    if (image.channels != 3 && image.channels != 1) {
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": writeExr needs a 1- or 3-channel image, got " +
                        std::to_string(image.channels) + " channels");
    }
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != image.pixelCount() * image.channels) {
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": writeExr got an empty or inconsistent image (" +
                        std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
    }
    io_detail::requireParentFolder(file);
    io_detail::TemporaryFile temporary(io_detail::temporaryPathFor(file));
    try {
        static const char* const rgb[] = {"R", "G", "B"};
        static const char* const gray[] = {"Y"};
        const char* const* names = image.channels == 3 ? rgb : gray;

        Imf::Header header(image.width, image.height, 1.0f, Imath::V2f(0, 0), 1.0f,
                           Imf::INCREASING_Y, Imf::ZIP_COMPRESSION);
        for (int c = 0; c < image.channels; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        }
        const std::size_t xStride = sizeof(float) * image.channels;
        const std::size_t yStride = xStride * image.width;
        Imf::FrameBuffer frameBuffer;
        for (int c = 0; c < image.channels; ++c) {
            // OpenEXR's Slice takes a mutable pointer but only reads from it when writing.
            frameBuffer.insert(names[c], Imf::Slice(Imf::FLOAT,
                                                    const_cast<char*>(reinterpret_cast<const char*>(
                                                        image.pixels.data() + c)),
                                                    xStride, yStride));
        }
        {
            Imf::OutputFile output(temporary.path().c_str(), header, Imf::globalThreadCount());
            output.setFrameBuffer(frameBuffer);
            output.writePixels(image.height);
        }  // the destructor finishes the file before the rename
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": cannot write: " + e.what());
    }
    temporary.commitTo(file);
}

}  // namespace rtd
