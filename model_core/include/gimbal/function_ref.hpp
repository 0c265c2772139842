// A non-owning reference to a callable, for callbacks on the hot path: std::function stores a lambda
// with more than two captures on the heap, and the FMU allocates nothing inside doStep after the first
// (docs/benchmarks.md; tests/fmu/test_no_allocation_in_do_step.py). The callable must outlive the call
// that receives the reference.
#pragma once

#include <type_traits>
#include <utility>

namespace gimbal {

template <class Signature>
class FunctionRef;

template <class Result, class... Arguments>
class FunctionRef<Result(Arguments...)> {
public:
    template <class Callable,
              class = std::enable_if_t<!std::is_same_v<std::decay_t<Callable>, FunctionRef>>>
    FunctionRef(Callable&& callable)  // NOLINT: implicit, as std::function's
        : object_(const_cast<void*>(static_cast<const void*>(&callable))),
          call_([](void* object, Arguments... arguments) -> Result {
              return (*static_cast<std::remove_reference_t<Callable>*>(object))(
                  std::forward<Arguments>(arguments)...);
          }) {}

    Result operator()(Arguments... arguments) const { return call_(object_, std::forward<Arguments>(arguments)...); }

private:
    void* object_;
    Result (*call_)(void*, Arguments...);
};

}  // namespace gimbal
