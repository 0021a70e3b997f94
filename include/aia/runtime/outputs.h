// The commands' output files and folders: checked before any work, locked
// while a job writes them.
#ifndef AIA_RUNTIME_OUTPUTS_H_
#define AIA_RUNTIME_OUTPUTS_H_

#include <string>
#include <vector>

namespace aia {

// Checks an output file named by a flag before any work: InputError (exit
// code 2) naming the flag when the path exists and is not a regular file.
void CheckOutputFile(const std::string& path, const std::string& flag);

// The same for every file a command writes (each command lists all of its
// outputs and calls this before any work): a FIFO, device or folder at any
// of `paths` is InputError naming the flag, the file and what it is
// (opening a FIFO would block; renaming onto it would replace it).
// `written` says how the files come from the flag ("written into the output
// folder").
void CheckOutputFiles(const std::vector<std::string>& paths,
                      const std::string& flag, const std::string& written = "");

// Creates an output folder named by a flag; InputError (exit code 2) naming
// the flag when it cannot be created or written. With `lock`, the folder is
// this process's until it ends (an flock on the folder: a second job
// writing into it is refused with an InputError), and temporary files that
// killed jobs left there are removed.
void MakeOutputDir(const std::string& dir, const std::string& flag,
                   bool lock = false);

// Locks `path` (a folder, or a file that is created if needed) until the
// process ends; InputError naming the flag when another process holds it.
// Taking a path this process holds already does nothing.
void LockOutput(const std::string& path, const std::string& flag);

}  // namespace aia

#endif  // AIA_RUNTIME_OUTPUTS_H_
