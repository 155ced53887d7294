#pragma once
// A request gRPC could not parse into its message (malformed bytes, or nested deeper than
// protobuf's limit of 100 levels - a 100 000-level group is refused at level 100) is answered by
// gRPC with INTERNAL and no message; this interceptor makes that INVALID_ARGUMENT saying why.
#include <grpcpp/support/server_interceptor.h>

namespace mdem::server {

class ParseFailureInterceptorFactory
    : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override;
};

}  // namespace mdem::server
